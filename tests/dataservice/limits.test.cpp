// Limits and concurrency: streams at once, time per call, clients that stall
// or vanish mid-stream, and 16 clients reading different steps at the same
// time. The asan preset runs these too: a cancelled stream must leave
// nothing behind.
#include <atomic>
#include <mutex>
#include <thread>

#include <catch2/catch.hpp>
#include <grpcpp/grpcpp.h>

#include "crackvis/v1/data.grpc.pb.h"
#include "service_fixture.hpp"
#include "support/process.hpp"
#include <crackvis/dataservice_client/remote_dem_file.hpp>
#include <crackvis/dataservice_h5/catalogue.hpp>
#include <crackvis/dem/h5.hpp>

namespace crackvis::testing {
namespace {

namespace v1 = crackvis::v1;
using dataservice::Hyperslab;

v1::ReadRequest bigRead() {
  v1::ReadRequest request;
  request.set_file("big.h5");
  request.add_slabs()->set_dataset("/ramp");
  request.add_slabs()->set_dataset("/ramp");
  request.add_slabs()->set_dataset("/ramp");  // 48 MiB: more than flow control lets through
  return request;
}

TEST_CASE("Streams over the limit are refused with RESOURCE_EXHAUSTED until one ends",
          "[dataservice][integration]") {
  auto config = baseConfig();
  config.limits.maxConcurrentStreams = 1;
  auto server = startServer(config);
  auto stub = rawStub(*server);

  // A client that reads one chunk and stalls holds its stream.
  grpc::ClientContext stalled;
  auto reader = stub->Read(&stalled, bigRead());
  v1::ReadChunk chunk;
  REQUIRE(reader->Read(&chunk));
  REQUIRE(server->activeStreams() == 1);

  auto client = connect(clientOptions(*server));
  const Status refused = client.read("run.h5", {Hyperslab::whole("/bonds/pairs")}).status();
  CHECK(refused.code() == StatusCode::kResourceExhausted);
  CHECK_THAT(refused.message(), Catch::Contains("max_concurrent_streams"));
  CHECK(client.fetch("run.h5", {}).status().code() == StatusCode::kResourceExhausted);
  // Unary calls are not streams.
  CHECK(client.describe("run.h5").isOk());

  stalled.TryCancel();
  while (reader->Read(&chunk)) {
  }
  CHECK(reader->Finish().error_code() == grpc::StatusCode::CANCELLED);
  REQUIRE(waitUntil([&] { return server->activeStreams() == 0; }));
  requireServerHealthy(*server);
}

TEST_CASE("Streams share a memory budget (max_memory_bytes): one over it is refused",
          "[dataservice][integration]") {
  auto config = baseConfig();
  config.limits.maxMemoryBytes = dataservice::kStreamBufferBytes;  // room for one stream
  auto server = startServer(config);
  auto stub = rawStub(*server);
  grpc::ClientContext held;
  auto reader = stub->Read(&held, bigRead());
  v1::ReadChunk chunk;
  REQUIRE(reader->Read(&chunk));

  auto client = connect(clientOptions(*server));
  const Status refused = client.read("run.h5", {Hyperslab::whole("/bonds/pairs")}).status();
  CHECK(refused.code() == StatusCode::kResourceExhausted);
  CHECK_THAT(refused.message(), Catch::Contains("max_memory_bytes"));

  held.TryCancel();
  while (reader->Read(&chunk)) {
  }
  REQUIRE(waitUntil([&] { return server->activeStreams() == 0; }));
  // The reservation went back with the stream.
  CHECK(client.read("run.h5", {Hyperslab::whole("/bonds/pairs")}).isOk());
}

// A file of a few KB whose one chunked, never written float64 dataset has
// one row of 2^27 values (1 GiB when read).
void writeSparseRow(const std::string& path) {
  namespace h5 = dem::h5;
  std::lock_guard lock(dataservice::hdf5Mutex());
  h5::Handle file =
      h5::fileHandle(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  REQUIRE(file.valid());
  const hsize_t dims[2] = {1, hsize_t{1} << 27};
  const hsize_t chunk[2] = {1, hsize_t{1} << 16};
  h5::Handle space = h5::dataspaceHandle(H5Screate_simple(2, dims, nullptr));
  h5::Handle create = h5::propertyListHandle(H5Pcreate(H5P_DATASET_CREATE));
  REQUIRE(H5Pset_chunk(create.get(), 2, chunk) >= 0);
  h5::Handle dataset = h5::datasetHandle(H5Dcreate2(file.get(), "row", H5T_IEEE_F64LE, space.get(),
                                                    H5P_DEFAULT, create.get(), H5P_DEFAULT));
  REQUIRE(dataset.valid());
}

TEST_CASE("A Read of one 1 GiB row streams in pieces of at most 1 MiB",
          "[dataservice][integration]") {
  TempDir root;
  writeSparseRow(root.file("sparse.h5"));
  REQUIRE(std::filesystem::file_size(root.file("sparse.h5")) < 64 * 1024);
  auto config = baseConfig();
  config.dataRoot = root.path().string();
  auto server = startServer(config);
  auto stub = rawStub(*server);
  v1::ReadRequest request;
  request.set_file("sparse.h5");
  request.add_slabs()->set_dataset("/row");  // the whole (1, 2^27) dataset
  const std::uint64_t before = residentBytes();
  grpc::ClientContext context;
  auto reader = stub->Read(&context, request);
  v1::ReadChunk chunk;
  std::uint64_t expectedOffset = 0;
  for (int i = 0; i < 8; ++i) {
    REQUIRE(reader->Read(&chunk));
    CHECK(chunk.slab_bytes() == (std::uint64_t{1} << 30));
    CHECK(chunk.offset() == expectedOffset);
    CHECK(chunk.data().size() <= dataservice::kMaxChunkBytes);
    CHECK(chunk.data().find_first_not_of('\0') == std::string::npos);  // the fill value
    expectedOffset += chunk.data().size();
  }
  // Before, the server read the whole row into one buffer first.
  CHECK(residentBytes() < before + (std::uint64_t{256} << 20));
  context.TryCancel();
  while (reader->Read(&chunk)) {
  }
  REQUIRE(waitUntil([&] { return server->activeStreams() == 0; }));
  auto client = connect(clientOptions(*server));
  auto tail = client.read("sparse.h5", {{"/row", {0, (1 << 27) - 4}, {1, 4}}});
  INFO(tail.status().message());
  REQUIRE(tail.isOk());
  CHECK(tail->front().values<double>().value() == std::vector<double>(4, 0.0));
}

TEST_CASE("A stream that runs past the time limit is cancelled by the server",
          "[dataservice][integration]") {
  auto config = baseConfig();
  config.limits.maxCallSeconds = 0.5;
  auto server = startServer(config);
  auto stub = rawStub(*server);
  grpc::ClientContext context;
  auto reader = stub->Read(&context, bigRead());
  v1::ReadChunk chunk;
  REQUIRE(reader->Read(&chunk));
  // Stall past the limit: the server cancels even though no write completes.
  REQUIRE(waitUntil([&] { return server->activeStreams() == 0; }, 5.0));
  std::uint64_t more = 0;
  while (reader->Read(&chunk)) {
    more += chunk.data().size();
  }
  CHECK(more < 3 * (std::uint64_t{16} << 20));
  const grpc::Status status = reader->Finish();
  CHECK(status.error_code() == grpc::StatusCode::CANCELLED);
  // A short call still fits.
  requireServerHealthy(*server);
}

TEST_CASE("A client that disconnects mid-stream leaves no stream behind",
          "[dataservice][integration]") {
  auto server = startServer(baseConfig());
  for (int round = 0; round < 3; ++round) {
    auto stub = rawStub(*server);
    {
      HeldFetch fetch(*stub);
      REQUIRE(fetch.readMore());
    }  // cancelled as it goes
    {
      grpc::ClientContext context;
      auto read = stub->Read(&context, bigRead());
      v1::ReadChunk chunk;
      REQUIRE(read->Read(&chunk));
    }              // the context goes without Finish: the call is cancelled
    stub.reset();  // and the connection closed
    REQUIRE(waitUntil([&] { return server->activeStreams() == 0; }));
  }
  requireServerHealthy(*server);
}

TEST_CASE("16 concurrent clients reading different steps get correct data",
          "[dataservice][integration]") {
  const SampleRoot& sample = sampleRoot();
  auto server = startServer(baseConfig());
  constexpr int kClients = 16;
  constexpr int kRounds = 3;
  std::vector<std::string> failures(kClients);
  std::atomic<int> reads{0};
  std::vector<std::thread> threads;
  for (int c = 0; c < kClients; ++c) {
    threads.emplace_back([&, c] {
      auto client = dataservice::DataClient::connect(clientOptions(*server));
      if (!client) {
        failures[c] = client.status().message();
        return;
      }
      auto file = dataservice::RemoteDemFile::open(*client, "many.h5");
      if (!file) {
        failures[c] = file.status().message();
        return;
      }
      for (int round = 0; round < kRounds; ++round) {
        const int step = (c + round * 5) % kClients;
        auto state = file->readStep(step);
        if (!state) {
          failures[c] = state.status().message();
          return;
        }
        const dem::StepState& expected = sample.sample16.steps[static_cast<size_t>(step)];
        if (state->positions.size() != expected.positions.size() ||
            std::memcmp(state->positions.data(), expected.positions.data(),
                        expected.positions.size() * sizeof(dem::Vec3)) != 0 ||
            state->bondState != expected.bondState) {
          failures[c] = fmt::format("step {} differs", step);
          return;
        }
        ++reads;
      }
      auto bonds = file->bonds();
      if (!bonds || **bonds != sample.sample16.lattice.bonds) {
        failures[c] = "bond list differs";
      }
    });
  }
  for (auto& thread : threads) {
    thread.join();
  }
  for (int c = 0; c < kClients; ++c) {
    INFO("client " << c << ": " << failures[c]);
    CHECK(failures[c].empty());
  }
  CHECK(reads == kClients * kRounds);
  // A stream's slot is released when the server finishes it; a failed one
  // when gRPC is done with it, a moment after the client has its status.
  CHECK(waitUntil([&] { return server->activeStreams() == 0; }));
  requireServerHealthy(*server);
}

}  // namespace
}  // namespace crackvis::testing
