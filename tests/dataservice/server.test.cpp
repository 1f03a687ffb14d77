// The DataService end to end: a real server on a loopback port with mutual
// TLS and generated certificates, a real client, real HDF5 files. Listing,
// describing and reading must give exactly what reading the file directly
// gives; every bad input gets a status that names the input, and the server
// keeps answering afterwards.
#include <chrono>
#include <ctime>
#include <stdexcept>
#include <string_view>
#include <thread>

#include <catch2/catch.hpp>
#include <fcntl.h>
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <sys/stat.h>

#include "crackvis/v1/data.grpc.pb.h"
#include "service_fixture.hpp"
#include "support/process.hpp"
#include <crackvis/dataservice_client/remote_dem_file.hpp>
#include <crackvis/dem/dem_file.hpp>

namespace crackvis::testing {
namespace {

namespace v1 = crackvis::v1;
using dataservice::DataType;
using dataservice::Hyperslab;

TEST_CASE("A client makes its connection before its first call when asked to",
          "[dataservice][integration]") {
  auto server = startServer(baseConfig());
  auto lazy = connect(clientOptions(*server));
  auto eager = connect(clientOptions(*server));
  eager.startConnecting();
  // crackvis-render does this as it starts: its first user's first picture
  // does not wait for the TLS handshake.
  CHECK(waitUntil([&] { return eager.connected(); }, 10.0));
  CHECK_FALSE(lazy.connected());  // each client its own connection, made on the first call
  CHECK(lazy.checkHealth().isOk());
  CHECK(lazy.connected());
  CHECK(eager.checkHealth().isOk());
}

TEST_CASE("ListFiles lists the data root and never a link out of it",
          "[dataservice][integration]") {
  const SampleRoot& sample = sampleRoot();
  auto server = startServer(baseConfig());
  auto client = connect(clientOptions(*server));

  auto files = client.listFiles("", true);
  INFO(files.status().message());
  REQUIRE(files.isOk());
  std::vector<std::string> paths;
  for (const auto& file : *files) {
    paths.push_back(file.path);
  }
  CHECK(paths == std::vector<std::string>{"alice/a.h5", "alice/bob-link.h5", "big.h5", "bob/b.h5",
                                          "extlink.h5", "flat/run2d.h5", "inside-link.h5",
                                          "many.h5", "notes.txt", "run.h5", "truncated.h5"});
  for (const auto& file : *files) {
    INFO(file.path);
    CHECK(file.sizeBytes == std::filesystem::file_size(sample.file(file.path)));
    CHECK(file.isHdf5 == (file.path != "notes.txt"));
    CHECK(file.modifiedUnixSeconds > 1600000000);
  }

  auto top = client.listFiles("", false);
  REQUIRE(top.isOk());
  for (const auto& file : *top) {
    CHECK(file.path.find('/') == std::string::npos);
  }
  auto flat = client.listFiles("flat", true);
  REQUIRE(flat.isOk());
  REQUIRE(flat->size() == 1);
  CHECK(flat->front().path == "flat/run2d.h5");

  auto escape = client.listFiles("../", true);
  CHECK(escape.status().code() == StatusCode::kInvalidArgument);
  auto missing = client.listFiles("nowhere", true);
  CHECK(missing.status().code() == StatusCode::kNotFound);
  CHECK_THAT(missing.status().message(), Catch::Contains("nowhere"));
}

TEST_CASE("Describe returns the whole tree of a file in one call, as the file holds it",
          "[dataservice][integration]") {
  const SampleRoot& sample = sampleRoot();
  auto server = startServer(baseConfig());
  auto client = connect(clientOptions(*server));

  auto description = client.describe("run.h5");
  INFO(description.status().message());
  REQUIRE(description.isOk());
  CHECK(description->file == "run.h5");
  CHECK(description->sizeBytes == std::filesystem::file_size(sample.file("run.h5")));
  CHECK(description->format == "crackvis-dem");
  CHECK(description->formatVersion == 1);

  const auto n = sample.sample3d.lattice.particleCount();
  const auto m = sample.sample3d.lattice.bondCount();
  REQUIRE(description->steps.size() == 3);
  for (int k = 0; k < 3; ++k) {
    CHECK(description->steps[k].index == k);
    CHECK(description->steps[k].time == sample.sample3d.steps[k].time);
    CHECK(description->steps[k].group == dem::stepGroupPath(k));
  }
  // 4 time-independent datasets, the spatial index's 4 (v1.3) and 4 per
  // step (with the optional arrays).
  CHECK(description->datasets.size() == 4 + 4 + 3 * 4);
  struct Expected {
    std::string path;
    DataType dtype;
    std::vector<std::uint64_t> shape;
  };
  for (const Expected& expected :
       std::vector<Expected>{{"/particles/radius", DataType::kFloat64, {n}},
                             {"/bonds/pairs", DataType::kInt32, {m, 2}},
                             {"/bonds/strength", DataType::kFloat64, {m}},
                             {"/bonds/break_step", DataType::kInt32, {m}},
                             {"/index/box", DataType::kFloat64, {2, 3}},
                             {"/index/order", DataType::kInt32, {n}},
                             {"/index/coordinate", DataType::kFloat64, {n}},
                             {"/index/bond_start", DataType::kInt64, {n + 1}},
                             {"/steps/000002/positions", DataType::kFloat64, {n, 3}},
                             {"/steps/000002/bond_state", DataType::kUInt8, {m}},
                             {"/steps/000002/velocities", DataType::kFloat32, {n, 3}},
                             {"/steps/000002/bond_force", DataType::kFloat32, {m}}}) {
    INFO(expected.path);
    const auto* dataset = description->findDataset(expected.path);
    REQUIRE(dataset != nullptr);
    CHECK(dataset->dtype == expected.dtype);
    CHECK(dataset->dtypeName == dataservice::dataTypeName(expected.dtype));
    CHECK(dataset->shape == expected.shape);
    CHECK(dataset->chunkShape.empty());  // crackvis-dem is contiguous
  }
  const auto* root = description->findGroup("/");
  REQUIRE(root != nullptr);
  bool sawDimension = false;
  for (const auto& attribute : root->attributes) {
    if (attribute.name == "dimension") {
      sawDimension = true;
      CHECK(std::get<std::vector<std::int64_t>>(attribute.value) == std::vector<std::int64_t>{3});
    }
    if (attribute.name == "source") {
      CHECK(std::get<std::string>(attribute.value) == "crackvis tests");
    }
  }
  CHECK(sawDimension);
  REQUIRE(description->findGroup("/steps") != nullptr);
  CHECK(description->findGroup("/steps/000001") != nullptr);

  // Through a symlink inside the root: the same tree.
  auto linked = client.describe("inside-link.h5");
  REQUIRE(linked.isOk());
  CHECK(linked->datasets == description->datasets);
  CHECK(linked->steps == description->steps);
}

namespace {

// Writes `sample` over a file the server has read. A file that had settled
// (unchanged for 2 s: on a loaded machine, the server's start-up can take
// that long) stays open in an HDF5 worker until it has been idle for 2 s, and
// HDF5's file lock keeps a writer out meanwhile ("Resource temporarily
// unavailable"): a writer waits that out, as this one does.
void overwriteSample(const std::string& path, const SampleData& sample) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
  for (;;) {
    try {
      writeSample(path, sample);
      return;
    } catch (const std::runtime_error& error) {
      if (std::string_view(error.what()).find("Resource temporarily unavailable") ==
              std::string_view::npos ||
          std::chrono::steady_clock::now() > deadline) {
        throw;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
}

// Rewrites `path` in place with the same layout and new step times, then
// gives it back its old modification time: the same size, inode and mtime,
// other contents (and a new status-change time, which no call can set).
void rewriteKeepingStamp(const std::string& path, SampleData sample, double timeShift) {
  struct stat before {};
  REQUIRE(::stat(path.c_str(), &before) == 0);
  for (auto& step : sample.steps) {
    step.time += timeShift;
  }
  overwriteSample(path, sample);
  const struct timespec times[2] = {before.st_atim, before.st_mtim};
  REQUIRE(::utimensat(AT_FDCWD, path.c_str(), times, 0) == 0);
  struct stat after {};
  REQUIRE(::stat(path.c_str(), &after) == 0);
  REQUIRE(after.st_ino == before.st_ino);
  REQUIRE(after.st_size == before.st_size);
}

double firstTime(const Result<dataservice::FileDescription>& description) {
  REQUIRE(description.isOk());
  REQUIRE(!description->steps.empty());
  return description->steps.front().time;
}

}  // namespace

TEST_CASE("Describe answers an unchanged file from its held answer and walks a changed one",
          "[dataservice][integration]") {
  TempDir root;
  const std::string path = (root.path() / "live.h5").string();
  const SampleData sample = makeSample(3, 2);
  writeSample(path, sample);
  // Answers are held only for files that settled (modified two seconds or
  // more ago): this one was, an hour ago.
  const struct timespec anHourAgo[2] = {{::time(nullptr) - 3600, 0}, {::time(nullptr) - 3600, 0}};
  REQUIRE(::utimensat(AT_FDCWD, path.c_str(), anHourAgo, 0) == 0);
  auto config = baseConfig();
  config.dataRoot = root.path().string();
  auto server = startServer(config);
  auto client = connect(clientOptions(*server));
  const double t0 = sample.steps.front().time;
  CHECK(firstTime(client.describe("live.h5")) == t0);

  SECTION("a rewrite that restores size, inode and mtime is walked again: its ctime moved") {
    rewriteKeepingStamp(path, sample, 1.0);
    CHECK(firstTime(client.describe("live.h5")) == t0 + 1.0);
    // uncached walks the file anyway, and its answer replaces the held one.
    rewriteKeepingStamp(path, sample, 2.0);
    CHECK(firstTime(client.describe("live.h5", true)) == t0 + 2.0);
    CHECK(firstTime(client.describe("live.h5")) == t0 + 2.0);
  }
  SECTION("a file that grew is walked again") {
    overwriteSample(path, makeSample(3, 4));
    auto grown = client.describe("live.h5");
    REQUIRE(grown.isOk());
    CHECK(grown->steps.size() == 4);
  }
  SECTION("a file modified in the last two seconds is walked every time") {
    // The file system's clock is coarse: a second write within its tick
    // would keep the stamp, so a file still being written is never held.
    const struct timespec now[2] = {{0, UTIME_NOW}, {0, UTIME_NOW}};
    REQUIRE(::utimensat(AT_FDCWD, path.c_str(), now, 0) == 0);
    CHECK(firstTime(client.describe("live.h5")) == t0);
    rewriteKeepingStamp(path, sample, 3.0);
    CHECK(firstTime(client.describe("live.h5")) == t0 + 3.0);
  }
  SECTION("a removed file is NOT_FOUND, not its held answer") {
    std::filesystem::remove(path);
    auto gone = client.describe("live.h5");
    CHECK(gone.status().code() == StatusCode::kNotFound);
  }
  SECTION("without a cache every Describe walks the file") {
    server.reset();
    config.limits.describeCacheBytes = 0;
    server = startServer(config);
    auto uncachedClient = connect(clientOptions(*server));
    CHECK(firstTime(uncachedClient.describe("live.h5")) == t0);
    rewriteKeepingStamp(path, sample, 2.0);
    CHECK(firstTime(uncachedClient.describe("live.h5")) == t0 + 2.0);
  }
}

TEST_CASE("Read returns hyperslabs bit-identical to reading the file directly",
          "[dataservice][integration]") {
  const SampleRoot& sample = sampleRoot();
  const std::string path = sample.file("run.h5");
  auto server = startServer(baseConfig());
  auto client = connect(clientOptions(*server));

  SECTION("whole datasets of every type, several in one call") {
    auto arrays = client.read(
        "run.h5",
        {Hyperslab::whole("/steps/000002/positions"), Hyperslab::whole("/steps/000002/bond_state"),
         Hyperslab::whole("/bonds/pairs"), Hyperslab::whole("/steps/000001/velocities"),
         Hyperslab::whole("/bonds/break_step")});
    INFO(arrays.status().message());
    REQUIRE(arrays.isOk());
    REQUIRE(arrays->size() == 5);
    const auto n = sample.sample3d.lattice.particleCount();
    CHECK((*arrays)[0].shape == std::vector<std::uint64_t>{n, 3});
    CHECK((*arrays)[0].dtype == DataType::kFloat64);
    CHECK(bitIdentical((*arrays)[0].values<double>().value(),
                       readDirect<double>(path, "/steps/000002/positions")));
    CHECK(bitIdentical((*arrays)[1].values<std::uint8_t>().value(),
                       readDirect<std::uint8_t>(path, "/steps/000002/bond_state")));
    CHECK(bitIdentical((*arrays)[2].values<std::int32_t>().value(),
                       readDirect<std::int32_t>(path, "/bonds/pairs")));
    CHECK(bitIdentical((*arrays)[3].values<float>().value(),
                       readDirect<float>(path, "/steps/000001/velocities")));
    CHECK(bitIdentical((*arrays)[4].values<std::int32_t>().value(),
                       readDirect<std::int32_t>(path, "/bonds/break_step")));
    // The wrong type is refused, not reinterpreted.
    CHECK((*arrays)[0].values<float>().status().code() == StatusCode::kInvalidArgument);
  }

  SECTION("a block of rows and a column: the slab's elements in C order") {
    auto arrays = client.read("run.h5", {{"/steps/000001/positions", {3, 0}, {7, 3}},
                                         {"/steps/000001/positions", {0, 1}, {20, 1}}});
    INFO(arrays.status().message());
    REQUIRE(arrays.isOk());
    const auto all = readDirect<double>(path, "/steps/000001/positions");
    std::vector<double> rows(all.begin() + 9, all.begin() + 30);
    std::vector<double> column;
    for (int i = 0; i < 20; ++i) {
      column.push_back(all[static_cast<size_t>(3 * i + 1)]);
    }
    CHECK((*arrays)[0].shape == std::vector<std::uint64_t>{7, 3});
    CHECK(bitIdentical((*arrays)[0].values<double>().value(), rows));
    CHECK((*arrays)[1].shape == std::vector<std::uint64_t>{20, 1});
    CHECK(bitIdentical((*arrays)[1].values<double>().value(), column));
  }

  SECTION("a 16 MiB dataset arrives in chunks of at most 1 MiB, in order") {
    v1::ReadRequest request;
    request.set_file("big.h5");
    request.add_slabs()->set_dataset("/ramp");
    v1::Hyperslab* wide = request.add_slabs();
    wide->set_dataset("/wide");  // rows of 1.2 MB: one piece per row, sent in slices
    auto stub = v1::DataService::NewStub(rawChannel(*server));
    grpc::ClientContext context;
    auto reader = stub->Read(&context, request);
    v1::ReadChunk chunk;
    std::vector<std::string> data(2);
    std::vector<int> chunks(2, 0);
    while (reader->Read(&chunk)) {
      REQUIRE(chunk.slab_index() < 2);
      CHECK(chunk.data().size() <= dataservice::kMaxChunkBytes);
      CHECK(chunk.data().size() > 0);
      CHECK(chunk.offset() == data[chunk.slab_index()].size());
      CHECK(chunk.dtype() == v1::FLOAT64);
      data[chunk.slab_index()] += chunk.data();
      ++chunks[chunk.slab_index()];
    }
    REQUIRE(reader->Finish().ok());
    CHECK(chunks[0] == 16);
    CHECK(chunks[1] == 6);
    const auto ramp = readDirect<double>(sampleRoot().file("big.h5"), "/ramp");
    REQUIRE(data[0].size() == ramp.size() * sizeof(double));
    CHECK(std::memcmp(data[0].data(), ramp.data(), data[0].size()) == 0);
    const auto wideValues = readDirect<double>(sampleRoot().file("big.h5"), "/wide");
    REQUIRE(data[1].size() == wideValues.size() * sizeof(double));
    CHECK(std::memcmp(data[1].data(), wideValues.data(), data[1].size()) == 0);
  }
}

TEST_CASE("Fetch streams the whole file byte for byte", "[dataservice][integration]") {
  auto server = startServer(baseConfig());
  auto client = connect(clientOptions(*server));
  for (const std::string name : {"run.h5", "big.h5"}) {
    INFO(name);
    const auto expected = fileBytes(sampleRoot().file(name));
    std::vector<std::byte> received;
    std::size_t largestChunk = 0;
    auto bytes = client.fetch(name, [&](std::uint64_t offset, const std::byte* data,
                                        std::size_t size, std::uint64_t total) {
      CHECK(offset == received.size());
      CHECK(total == expected.size());
      largestChunk = std::max(largestChunk, size);
      received.insert(received.end(), data, data + size);
      return Status::ok();
    });
    INFO(bytes.status().message());
    REQUIRE(bytes.isOk());
    CHECK(*bytes == expected.size());
    CHECK(largestChunk <= dataservice::kMaxChunkBytes);
    CHECK(received == expected);
  }
}

TEST_CASE("The client library reads a crackvis-dem file as typed DEM arrays",
          "[dataservice][integration]") {
  const SampleRoot& sample = sampleRoot();
  auto server = startServer(baseConfig());
  auto client = connect(clientOptions(*server));
  auto file = dataservice::RemoteDemFile::open(client, "run.h5");
  INFO(file.status().message());
  REQUIRE(file.isOk());
  CHECK(file->dimension() == 3);
  CHECK(file->particleCount() ==
        static_cast<std::int64_t>(sample.sample3d.lattice.particleCount()));
  CHECK(file->bondCount() == static_cast<std::int64_t>(sample.sample3d.lattice.bondCount()));
  CHECK(file->stepCount() == 3);
  CHECK_FALSE(file->bondsLoaded());

  auto step = file->readStep(2);  // with the bond list, in the same call
  INFO(step.status().message());
  REQUIRE(step.isOk());
  CHECK(file->bondsLoaded());
  CHECK(step->time == sample.sample3d.steps[2].time);
  CHECK(step->positions == sample.sample3d.steps[2].positions);
  CHECK(step->bondState == sample.sample3d.steps[2].bondState);
  auto bonds = file->bonds();
  REQUIRE(bonds.isOk());
  CHECK(**bonds == sample.sample3d.lattice.bonds);
  // Velocities and bond forces only when asked for (a view colours by
  // them), in the same Read; the break steps per file.
  CHECK(step->velocities.empty());
  CHECK(step->bondForce.empty());
  dataservice::StepExtras extras;
  extras.velocities = true;
  extras.bondForce = true;
  auto withExtras = file->readStep(1, extras);
  INFO(withExtras.status().message());
  REQUIRE(withExtras.isOk());
  CHECK(withExtras->positions == sample.sample3d.steps[1].positions);
  CHECK(withExtras->bondState == sample.sample3d.steps[1].bondState);
  CHECK(withExtras->velocities == sample.sample3d.steps[1].velocities);
  CHECK(withExtras->bondForce == sample.sample3d.steps[1].bondForce);
  auto breakSteps = file->breakSteps();
  REQUIRE(breakSteps.isOk());
  auto local = dem::DemFileReader::open(sample.file("run.h5"));
  REQUIRE(local.isOk());
  CHECK(*breakSteps == *local->readBreakSteps());

  auto block = file->positions(1, 5, 10);
  REQUIRE(block.isOk());
  CHECK(*block == std::vector<dem::Vec3>(sample.sample3d.steps[1].positions.begin() + 5,
                                         sample.sample3d.steps[1].positions.begin() + 15));
  auto radii = file->radii();
  REQUIRE(radii.isOk());
  CHECK(*radii == sample.sample3d.lattice.radius);
  CHECK(file->readStep(3).status().code() == StatusCode::kOutOfRange);

  auto notDem = dataservice::RemoteDemFile::open(client, "big.h5");
  CHECK(notDem.status().code() == StatusCode::kFailedPrecondition);
  CHECK_THAT(notDem.status().message(), Catch::Contains("not a crackvis-dem file"));
}

TEST_CASE("Health checking and server reflection are served", "[dataservice][integration]") {
  auto server = startServer(baseConfig());
  auto client = connect(clientOptions(*server));
  CHECK(client.checkHealth().isOk());
  CHECK(client.checkHealth("grpc.health.v1.Health").isOk() ==
        client.checkHealth("grpc.health.v1.Health").isOk());

  // grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo with
  // list_services = "" (field 7): the reply names the DataService.
  auto channel = rawChannel(*server);
  grpc::GenericStub stub(channel);
  grpc::CompletionQueue queue;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  auto call = stub.PrepareCall(
      &context, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo", &queue);
  int tag = 0;
  void* got = nullptr;
  bool ok = false;
  auto step = [&](int expected) {
    REQUIRE(queue.Next(&got, &ok));
    REQUIRE(got == reinterpret_cast<void*>(static_cast<intptr_t>(expected)));
    return ok;
  };
  call->StartCall(reinterpret_cast<void*>(static_cast<intptr_t>(++tag)));
  REQUIRE(step(tag));
  const char request[] = {0x3a, 0x00};
  grpc::Slice slice(request, sizeof(request));
  grpc::ByteBuffer message(&slice, 1);
  call->Write(message, reinterpret_cast<void*>(static_cast<intptr_t>(++tag)));
  REQUIRE(step(tag));
  grpc::ByteBuffer reply;
  call->Read(&reply, reinterpret_cast<void*>(static_cast<intptr_t>(++tag)));
  REQUIRE(step(tag));
  std::vector<grpc::Slice> slices;
  REQUIRE(reply.Dump(&slices).ok());
  std::string text;
  for (const auto& s : slices) {
    text.append(reinterpret_cast<const char*>(s.begin()), s.size());
  }
  CHECK_THAT(text, Catch::Contains("crackvis.v1.DataService"));
  CHECK_THAT(text, Catch::Contains("grpc.health.v1.Health"));
  call->WritesDone(reinterpret_cast<void*>(static_cast<intptr_t>(++tag)));
  step(tag);
  grpc::Status status;
  call->Finish(&status, reinterpret_cast<void*>(static_cast<intptr_t>(++tag)));
  step(tag);
  CHECK(status.ok());
  queue.Shutdown();
  while (queue.Next(&got, &ok)) {
  }
}

TEST_CASE("A Describe request that is no DescribeRequest is refused, and the server keeps serving",
          "[dataservice][integration]") {
  // Describe takes its request as bytes (it answers with the held bytes):
  // the parse is the handler's, so a malformed request must still be
  // INVALID_ARGUMENT.
  auto server = startServer(baseConfig());
  auto channel = rawChannel(*server);
  grpc::GenericStub stub(channel);
  grpc::CompletionQueue queue;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  const char garbage[] = {0x0a, 0x7f, 'x'};  // field 1 announces 127 bytes and holds 1
  grpc::Slice slice(garbage, sizeof(garbage));
  const grpc::ByteBuffer request(&slice, 1);
  auto call = stub.PrepareUnaryCall(&context, "/crackvis.v1.DataService/Describe", request, &queue);
  call->StartCall();
  grpc::ByteBuffer reply;
  grpc::Status status;
  call->Finish(&reply, &status, reinterpret_cast<void*>(1));
  void* got = nullptr;
  bool ok = false;
  REQUIRE(queue.Next(&got, &ok));
  CHECK(status.error_code() == grpc::StatusCode::INVALID_ARGUMENT);
  CHECK_THAT(status.error_message(), Catch::Contains("malformed crackvis.v1.DescribeRequest"));
  queue.Shutdown();
  while (queue.Next(&got, &ok)) {
  }
  auto client = connect(clientOptions(*server));
  CHECK(client.describe("run.h5").isOk());
  requireServerHealthy(*server);
}

struct BadInput {
  std::string name;
  std::string file;
  std::vector<Hyperslab> slabs;  // empty: the call is Describe and Fetch, else Read
  StatusCode code;
  std::vector<std::string> messageParts;
};

TEST_CASE("Each bad input gets a status naming it, and the server keeps serving",
          "[dataservice][integration]") {
  auto config = baseConfig();
  config.limits.maxReadBytes = 4 << 20;
  config.limits.maxFetchBytes = 8 << 20;
  auto server = startServer(config);
  auto client = connect(clientOptions(*server));
  const auto n = static_cast<std::int64_t>(sampleRoot().sample3d.lattice.particleCount());
  const std::string positions = "/steps/000000/positions";
  const std::vector<BadInput> inputs = {
      {"a path with ..", "../run.h5", {}, StatusCode::kInvalidArgument, {"'../run.h5'", "'..'"}},
      {"a path with .. inside",
       "flat/../../etc/passwd",
       {},
       StatusCode::kInvalidArgument,
       {"'..'"}},
      {"an absolute path",
       "/etc/passwd",
       {},
       StatusCode::kInvalidArgument,
       {"'/etc/passwd'", "absolute"}},
      {"a symlink out of the root",
       "escape.h5",
       {},
       StatusCode::kPermissionDenied,
       {"'escape.h5'", "outside the data root"}},
      {"a missing file", "nothing.h5", {}, StatusCode::kNotFound, {"'nothing.h5'"}},
      {"a folder", "flat", {}, StatusCode::kInvalidArgument, {"'flat'", "not a regular file"}},
      {"an empty path", "", {}, StatusCode::kInvalidArgument, {"empty path"}},
      {"a file that is not HDF5",
       "notes.txt",
       {},
       StatusCode::kFailedPrecondition,
       {"notes.txt", "not an HDF5 file"}},
      {"a missing dataset",
       "run.h5",
       {Hyperslab::whole("/steps/000099/positions")},
       StatusCode::kNotFound,
       {"/steps/000099/positions", "missing in run.h5"}},
      {"a group instead of a dataset",
       "run.h5",
       {Hyperslab::whole("/steps")},
       StatusCode::kInvalidArgument,
       {"/steps", "group, not a dataset"}},
      {"a relative dataset name",
       "run.h5",
       {Hyperslab::whole("bonds/pairs")},
       StatusCode::kInvalidArgument,
       {"'bonds/pairs'", "absolute path"}},
      {"a hyperslab past the end",
       "run.h5",
       {{positions, {n - 2, 0}, {5, 3}}},
       StatusCode::kInvalidArgument,
       {positions, fmt::format("start [{},0] count [5,3]", n - 2), fmt::format("shape [{},3]", n)}},
      {"a start past the end",
       "run.h5",
       {{positions, {n, 0}, {1, 3}}},
       StatusCode::kInvalidArgument,
       {"lies outside", fmt::format("[{},3]", n)}},
      {"a zero count",
       "run.h5",
       {{positions, {0, 0}, {0, 3}}},
       StatusCode::kInvalidArgument,
       {"count[0] = 0", "at least 1"}},
      {"a negative count",
       "run.h5",
       {{positions, {0, 0}, {4, -1}}},
       StatusCode::kInvalidArgument,
       {"count[1] = -1"}},
      {"a negative start",
       "run.h5",
       {{positions, {-1, 0}, {1, 3}}},
       StatusCode::kInvalidArgument,
       {"start[0] = -1", "negative"}},
      {"a rank mismatch",
       "run.h5",
       {{positions, {0}, {1}}},
       StatusCode::kInvalidArgument,
       {"rank 2"}},
      {"a read over the byte limit",
       "big.h5",
       {Hyperslab::whole("/ramp")},
       StatusCode::kResourceExhausted,
       {"big.h5", "4.00 MiB", "limit"}},
      {"an external link out of the file",
       "extlink.h5",
       {Hyperslab::whole("/outside")},
       StatusCode::kPermissionDenied,
       {"/outside", "external link"}},
      {"no hyperslab at all", "run.h5", {Hyperslab{}}, StatusCode::kInvalidArgument, {"run.h5"}},
  };
  for (const BadInput& input : inputs) {
    DYNAMIC_SECTION(input.name) {
      std::vector<Status> statuses;
      if (input.slabs.empty()) {
        statuses.push_back(client.describe(input.file).status());
        statuses.push_back(client.read(input.file, {Hyperslab::whole("/bonds/pairs")}).status());
        statuses.push_back(client.fetch(input.file, {}).status());
      } else {
        statuses.push_back(client.read(input.file, input.slabs).status());
      }
      for (const Status& status : statuses) {
        INFO(status.message());
        CHECK(status.code() == input.code);
        for (const std::string& part : input.messageParts) {
          CHECK_THAT(status.message(), Catch::Contains(part));
        }
      }
      requireServerHealthy(*server);
    }
  }

  SECTION("a truncated HDF5 file") {
    const Status describe = client.describe("truncated.h5").status();
    const Status read = client.read("truncated.h5", {Hyperslab::whole("/bonds/pairs")}).status();
    for (const Status& status : {describe, read}) {
      INFO(status.message());
      CHECK(status.code() == StatusCode::kFailedPrecondition);
      CHECK_THAT(status.message(), Catch::Contains("truncated.h5") && Catch::Contains("truncated"));
    }
    requireServerHealthy(*server);
  }

  SECTION("a fetch over the byte limit") {
    const Status status = client.fetch("big.h5", {}).status();
    CHECK(status.code() == StatusCode::kResourceExhausted);
    CHECK_THAT(status.message(), Catch::Contains("big.h5") && Catch::Contains("8.00 MiB"));
    requireServerHealthy(*server);
  }
}

}  // namespace
}  // namespace crackvis::testing
