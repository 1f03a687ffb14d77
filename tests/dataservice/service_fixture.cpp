#include "service_fixture.hpp"

#include <cstdlib>
#include <fstream>
#include <mutex>
#include <stdexcept>

#include <catch2/catch.hpp>

#include "support/h5_tamper.hpp"
#include "support/process.hpp"
#include <crackvis/dataservice_h5/catalogue.hpp>
#include <crackvis/dem/h5.hpp>

namespace crackvis::testing {
namespace fs = std::filesystem;
namespace h5 = dem::h5;
using dataservice::DataType;

namespace {

void writeBigFile(const std::string& path) {
  h5::quietHdf5();
  h5::Handle file =
      h5::fileHandle(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  if (!file.valid()) {
    throw std::runtime_error("cannot create " + path);
  }
  std::vector<double> ramp(std::size_t{1} << 21);
  for (std::size_t i = 0; i < ramp.size(); ++i) {
    ramp[i] = 0.5 * static_cast<double>(i);
  }
  std::vector<double> wide(3 * 150000);
  for (std::size_t i = 0; i < wide.size(); ++i) {
    wide[i] = -1.0 * static_cast<double>(i);
  }
  if (!h5::writeDataset(file.get(), "ramp", h5::ElementType::kFloat64, {ramp.size()},
                        ramp.data()) ||
      !h5::writeDataset(file.get(), "wide", h5::ElementType::kFloat64, {3, 150000}, wide.data())) {
    throw std::runtime_error("cannot write " + path);
  }
}

void writeExternalLinkFile(const std::string& path, const std::string& target) {
  h5::Handle file =
      h5::fileHandle(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  std::vector<double> data = {1.0, 2.0};
  if (!file.valid() ||
      !h5::writeDataset(file.get(), "inside", h5::ElementType::kFloat64, {2}, data.data()) ||
      H5Lcreate_external(target.c_str(), "/data", file.get(), "outside", H5P_DEFAULT, H5P_DEFAULT) <
          0) {
    throw std::runtime_error("cannot write " + path);
  }
}

void writeSecret(const std::string& path) {
  h5::Handle file =
      h5::fileHandle(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  std::vector<double> data = {42.0, 43.0, 44.0};
  if (!file.valid() ||
      !h5::writeDataset(file.get(), "data", h5::ElementType::kFloat64, {3}, data.data())) {
    throw std::runtime_error("cannot write " + path);
  }
}

std::unique_ptr<SampleRoot> makeSampleRoot() {
  auto sample = std::make_unique<SampleRoot>();
  std::lock_guard lock(dataservice::hdf5Mutex());
  const fs::path root = sample->root.path();
  fs::create_directories(root / "flat");
  fs::create_directories(root / "alice");
  fs::create_directories(root / "bob");
  sample->sample3d = makeSample(3, 3);
  writeSample(sample->file("run.h5"), sample->sample3d);
  writeSample(sample->file("flat/run2d.h5"), makeSample(2, 2));
  sample->sample16 = makeSample(3, 16);
  writeSample(sample->file("many.h5"), sample->sample16);
  writeBigFile(sample->file("big.h5"));
  std::ofstream(sample->file("notes.txt")) << "plain text, not HDF5\n";
  fs::copy_file(root / "run.h5", root / "truncated.h5");
  truncateFile(sample->file("truncated.h5"), 0.5);
  fs::copy_file(root / "run.h5", root / "alice/a.h5");
  fs::copy_file(root / "run.h5", root / "bob/b.h5");
  fs::create_symlink("../bob/b.h5", root / "alice/bob-link.h5");
  fs::create_symlink("run.h5", root / "inside-link.h5");
  const std::string secret = (sample->outside.path() / "secret.h5").string();
  writeSecret(secret);
  fs::create_symlink(secret, root / "escape.h5");
  writeExternalLinkFile(sample->file("extlink.h5"), secret);
  return sample;
}

}  // namespace

const fs::path& certificateDir() {
  static TempDir dir;
  static std::once_flag once;
  std::call_once(once, [] {
    const ProcessResult result = runProcess({"bash", CRACKVIS_MAKE_DEV_CERTS, dir.path().string(),
                                             "--test-extras", "--client", "crackvis-render"});
    if (result.exitCode != 0) {
      throw std::runtime_error("make-dev-certs.sh failed: " + result.err);
    }
  });
  return dir.path();
}

tls::TlsFiles serverTls() {
  const fs::path& dir = certificateDir();
  return {(dir / "ca.pem").string(), (dir / "server.pem").string(), (dir / "server.key").string()};
}

tls::TlsFiles clientTls(const std::string& name, const std::string& ca) {
  const fs::path& dir = certificateDir();
  return {(dir / (ca + ".pem")).string(), (dir / (name + ".pem")).string(),
          (dir / (name + ".key")).string()};
}

const SampleRoot& sampleRoot() {
  static std::unique_ptr<SampleRoot> root = makeSampleRoot();
  return *root;
}

dataservice::ServerConfig baseConfig() {
  dataservice::ServerConfig config;
  config.listen = "127.0.0.1:0";
  config.dataRoot = sampleRoot().root.path().string();
  config.tls = serverTls();
  config.accessLog = "";
  return config;
}

std::shared_ptr<grpc::Channel> rawChannel(const dataservice::DataServer& server) {
  const auto tls = tls::loadTlsMaterial(clientTls()).value();
  grpc::SslCredentialsOptions ssl;
  ssl.pem_root_certs = tls.caPem;
  ssl.pem_cert_chain = tls.certPem;
  ssl.pem_private_key = tls.keyPem;
  grpc::ChannelArguments arguments;
  arguments.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
  return grpc::CreateCustomChannel(server.address(), grpc::SslCredentials(ssl), arguments);
}

std::unique_ptr<crackvis::v1::DataService::Stub> rawStub(const dataservice::DataServer& server) {
  return crackvis::v1::DataService::NewStub(rawChannel(server));
}

HeldFetch::HeldFetch(crackvis::v1::DataService::Stub& stub) {
  crackvis::v1::FetchRequest request;
  request.set_file("big.h5");
  m_reader = stub.Fetch(&m_context, request);
  REQUIRE(readMore());
}

std::unique_ptr<dataservice::DataServer> startServer(const dataservice::ServerConfig& config) {
  auto server = dataservice::DataServer::start(config);
  if (!server) {
    FAIL("server did not start: " << server.status().message());
  }
  return std::move(*server);
}

dataservice::ClientOptions clientOptions(const dataservice::DataServer& server,
                                         const std::string& certificate) {
  dataservice::ClientOptions options;
  options.target = server.address();
  options.tls = clientTls(certificate);
  options.timeoutSeconds = 20.0;
  return options;
}

dataservice::DataClient connect(const dataservice::ClientOptions& options) {
  auto client = dataservice::DataClient::connect(options);
  if (!client) {
    FAIL("cannot make a client: " << client.status().message());
  }
  return std::move(*client);
}

template <typename T>
std::vector<T> readDirect(const std::string& file, const std::string& dataset) {
  std::lock_guard lock(dataservice::hdf5Mutex());
  h5::quietHdf5();
  h5::Handle handle = h5::fileHandle(H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  h5::Handle data =
      h5::datasetHandle(handle.valid() ? H5Dopen2(handle.get(), dataset.c_str(), H5P_DEFAULT) : -1);
  if (!data.valid()) {
    throw std::runtime_error("readDirect: cannot open " + dataset + " in " + file);
  }
  h5::Handle space = h5::dataspaceHandle(H5Dget_space(data.get()));
  std::vector<T> values(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space.get())));
  hid_t type = H5T_NATIVE_DOUBLE;
  if constexpr (std::is_same_v<T, std::int32_t>) {
    type = H5T_NATIVE_INT32;
  } else if constexpr (std::is_same_v<T, std::uint8_t>) {
    type = H5T_NATIVE_UINT8;
  } else if constexpr (std::is_same_v<T, float>) {
    type = H5T_NATIVE_FLOAT;
  }
  if (H5Dread(data.get(), type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) < 0) {
    throw std::runtime_error("readDirect: cannot read " + dataset);
  }
  return values;
}
template std::vector<double> readDirect<double>(const std::string&, const std::string&);
template std::vector<float> readDirect<float>(const std::string&, const std::string&);
template std::vector<std::int32_t> readDirect<std::int32_t>(const std::string&, const std::string&);
template std::vector<std::uint8_t> readDirect<std::uint8_t>(const std::string&, const std::string&);

std::vector<std::byte> fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::byte> out(bytes.size());
  std::memcpy(out.data(), bytes.data(), bytes.size());
  return out;
}

void writeNestedGroups(const std::string& path, int levels) {
  std::lock_guard lock(dataservice::hdf5Mutex());
  namespace h5 = dem::h5;
  h5::Handle file =
      h5::fileHandle(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  REQUIRE(file.valid());
  std::vector<h5::Handle> groups;
  hid_t parent = file.get();
  for (int level = 0; level < levels; ++level) {
    groups.push_back(
        h5::groupHandle(H5Gcreate2(parent, "g", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT)));
    REQUIRE(groups.back().valid());
    parent = groups.back().get();
  }
  const double value = 1.0;
  REQUIRE(h5::writeDataset(parent, "bottom", h5::ElementType::kFloat64, {1}, &value).isOk());
}

void writeWideGroups(const std::string& path, int count) {
  std::lock_guard lock(dataservice::hdf5Mutex());
  namespace h5 = dem::h5;
  h5::Handle file =
      h5::fileHandle(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  REQUIRE(file.valid());
  for (int i = 0; i < count; ++i) {
    h5::Handle group = h5::groupHandle(H5Gcreate2(file.get(), fmt::format("g{}", i).c_str(),
                                                  H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    REQUIRE(group.valid());
  }
}

void requireServerHealthy(const dataservice::DataServer& server) {
  auto client = connect(clientOptions(server));
  const Status health = client.checkHealth();
  INFO(health.message());
  REQUIRE(health.isOk());
  auto arrays = client.read("run.h5", {dataservice::Hyperslab::whole("/steps/000001/positions")});
  INFO(arrays.status().message());
  REQUIRE(arrays.isOk());
  const auto expected = readDirect<double>(sampleRoot().file("run.h5"), "/steps/000001/positions");
  REQUIRE(bitIdentical(arrays->front().values<double>().value(), expected));
}

}  // namespace crackvis::testing
