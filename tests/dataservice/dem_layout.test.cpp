// The crackvis-dem layout checked in one place: the local reader, the remote
// reader (through a real crackvis-data) and the render server's step sources
// give one status code and one message for the same problem.
#include <cstring>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "service_fixture.hpp"
#include "support/h5_tamper.hpp"
#include <crackvis/dataservice_client/remote_dem_file.hpp>
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/source/step_source.hpp>

namespace crackvis::testing {
namespace {

namespace v1 = crackvis::v1;

TEST_CASE("A step out of range is OUT_OF_RANGE with one message from every reader",
          "[dataservice][integration]") {
  const SampleRoot& sample = sampleRoot();
  auto server = startServer(baseConfig());
  auto client = connect(clientOptions(*server));
  const std::string expected = "run.h5: step 3 out of range (the file has steps 0..2)";

  auto remote = dataservice::RemoteDemFile::open(client, "run.h5");
  REQUIRE(remote.isOk());
  auto local = dem::DemFileReader::open(sample.file("run.h5"));
  REQUIRE(local.isOk());
  auto remoteSource = source::openRemoteSource(client, "run.h5");
  REQUIRE(remoteSource.isOk());
  auto localSource = source::openLocalSource(sample.file("run.h5"));
  REQUIRE(localSource.isOk());

  const std::vector<std::pair<std::string, Status>> answers = {
      {"remote readStep", remote->readStep(3).status()},
      {"remote positions", remote->positions(-1).status()},
      {"remote bondState", remote->bondState(3).status()},
      {"local readStep", local->readStep(3).status()},
      {"local readBondState", local->readBondState(-1).status()},
      {"remote step source", (*remoteSource)->read(3).status()},
      {"local step source", (*localSource)->read(3).status()},
  };
  for (const auto& [reader, status] : answers) {
    INFO(reader << ": " << status.message());
    CHECK(status.code() == StatusCode::kOutOfRange);
    // The local reader names the file by its path on this machine.
    const bool isLocal = reader.rfind("local", 0) == 0;
    const std::string file = isLocal ? sample.file("run.h5") : "run.h5";
    const bool negative = reader == "remote positions" || reader == "local readBondState";
    CHECK(status.message() == fmt::format("{}: step {} out of range (the file has steps 0..2)",
                                          file, negative ? -1 : 3));
  }
  CHECK(dem::checkStepInRange("run.h5", 3, 3).message() == expected);
  CHECK(dem::checkStepInRange("empty.h5", 0, 0).message() ==
        "empty.h5: step 0 out of range (the file has no steps)");
}

TEST_CASE("The local and the remote reader word a layout problem alike",
          "[dataservice][integration]") {
  TempDir root;
  const auto sample = writeSampleFile(root.file("bad.h5"), 3, 2);
  const auto bonds = static_cast<std::uint64_t>(sample.lattice.bondCount());
  replaceDataset(root.file("bad.h5"), "/steps/000001/bond_state", dem::h5::ElementType::kUInt8,
                 {bonds + 1});
  auto config = baseConfig();
  config.dataRoot = root.path().string();
  auto server = startServer(config);
  auto client = connect(clientOptions(*server));

  const std::string problem =
      fmt::format("dataset /steps/000001/bond_state has shape [{}], expected [{}] (N = {}, M = {})",
                  bonds + 1, bonds, sample.lattice.particleCount(), bonds);
  auto remote = dataservice::RemoteDemFile::open(client, "bad.h5");
  REQUIRE_FALSE(remote.isOk());
  CHECK(remote.status().code() == StatusCode::kFailedPrecondition);
  CHECK(remote.status().message() == "bad.h5: " + problem);

  auto local = dem::DemFileReader::open(root.file("bad.h5"));
  REQUIRE(local.isOk());
  const Status read = local->readStep(1).status();
  CHECK(read.code() == StatusCode::kFailedPrecondition);
  CHECK(read.message() == root.file("bad.h5") + ": " + problem);
}

TEST_CASE("The local and the remote step source give the cell decomposition the file records",
          "[dataservice][integration]") {
  TempDir root;
  writeSampleFile(root.file("none.h5"), 3, 2);  // its writer decided none
  writeSampleFile(root.file("lattice.h5"), 3, 2);
  setStringAttribute(root.file("lattice.h5"), dem::kSpatialIndexGroup, "decomposition", "lattice");
  writeSampleFile(root.file("triangulation.h5"), 3, 2);
  setStringAttribute(root.file("triangulation.h5"), dem::kSpatialIndexGroup, "decomposition",
                     "triangulation");
  auto config = baseConfig();
  config.dataRoot = root.path().string();
  auto server = startServer(config);
  auto client = connect(clientOptions(*server));

  for (const auto& [file, expected] : std::vector<std::pair<std::string, dem::CellDecomposition>>{
           {"none.h5", dem::CellDecomposition::kUnknown},
           {"lattice.h5", dem::CellDecomposition::kLattice},
           {"triangulation.h5", dem::CellDecomposition::kTriangulation}}) {
    INFO(file);
    auto remote = dataservice::RemoteDemFile::open(client, file);
    REQUIRE(remote.isOk());
    CHECK(remote->recordedDecomposition() == expected);
    auto remoteSource = source::openRemoteSource(client, file);
    REQUIRE(remoteSource.isOk());
    CHECK((*remoteSource)->recordedDecomposition() == expected);
    auto localSource = source::openLocalSource(root.file(file));
    REQUIRE(localSource.isOk());
    CHECK((*localSource)->recordedDecomposition() == expected);
  }
}

TEST_CASE("a compressed crackvis-dem file reads through the service in pieces, as written",
          "[dataservice][integration][v1.1]") {
  // 60,000 particles: a step's positions are 1.4 MB, more than one 1 MiB piece.
  TempDir root;
  const std::string path = root.file("packed.h5");
  dem::Lattice lattice;
  lattice.radius.assign(60000, 0.5);
  lattice.bonds = {{0, 1}, {1, 2}};
  dem::StepState step;
  for (int i = 0; i < 60000; ++i) {
    step.positions.push_back({i * 1.0, (i % 7) * 0.25, (i % 13) * 0.5});
  }
  step.bondState = {0, 1};
  {
    std::lock_guard lock(dataservice::hdf5Mutex());
    dem::DemMetadata metadata;
    metadata.storage.deflateLevel = 4;
    auto writer = dem::DemFileWriter::create(path, lattice, metadata);
    REQUIRE(writer);
    REQUIRE(writer->appendStep(step));
    REQUIRE(writer->close());
  }
  auto config = baseConfig();
  config.dataRoot = root.path().string();
  auto server = startServer(config);
  auto client = connect(clientOptions(*server));
  auto description = client.describe("packed.h5");
  REQUIRE(description);
  const auto* positions = description->findDataset("/steps/000000/positions");
  REQUIRE(positions != nullptr);
  CHECK_FALSE(positions->chunkShape.empty());  // stored chunked (and deflated)

  auto stub = rawStub(*server);
  v1::ReadRequest request;
  request.set_file("packed.h5");
  request.add_slabs()->set_dataset("/steps/000000/positions");
  grpc::ClientContext context;
  auto reader = stub->Read(&context, request);
  v1::ReadChunk chunk;
  std::string bytes;
  int pieces = 0;
  while (reader->Read(&chunk)) {
    CHECK(chunk.offset() == bytes.size());
    CHECK(chunk.data().size() <= (std::size_t{1} << 20));
    bytes += chunk.data();
    ++pieces;
  }
  REQUIRE(reader->Finish().ok());
  CHECK(pieces >= 2);
  REQUIRE(bytes.size() == step.positions.size() * sizeof(dem::Vec3));
  CHECK(std::memcmp(bytes.data(), step.positions.data(), bytes.size()) == 0);
}

}  // namespace
}  // namespace crackvis::testing
