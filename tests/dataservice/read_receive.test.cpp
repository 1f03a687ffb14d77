// How a Read is received and served without needless work: the client
// parses chunks off the wire straight into the caller's buffers (as protobuf
// defines the message, whatever the field order), a Read can be started
// before its buffers exist and checked chunk by chunk, and the catalogue
// keeps files open between calls without serving a changed file stale.
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <thread>

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <grpcpp/generic/async_generic_service.h>
#include <grpcpp/grpcpp.h>

#include "crackvis/v1/data.pb.h"
#include "service_fixture.hpp"
#include "support/h5_tamper.hpp"
#include "support/process.hpp"
#include <crackvis/dataservice_client/remote_dem_file.hpp>
#include <crackvis/dataservice_h5/catalogue.hpp>
#include <crackvis/dataservice_protocol/packed_chunk.hpp>

namespace crackvis::testing {
namespace {

namespace fs = std::filesystem;
namespace v1 = crackvis::v1;
using dataservice::DataClient;
using dataservice::Hyperslab;

// A stand-in for crackvis-data (plaintext, loopback) that answers every call
// with the given serialized messages, then OK: lets a test send chunks the
// real server never would.
class ScriptedServer {
 public:
  explicit ScriptedServer(std::vector<std::string> messages) : m_service(std::move(messages)) {
    grpc::ServerBuilder builder;
    builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &m_port);
    builder.RegisterCallbackGenericService(&m_service);
    m_server = builder.BuildAndStart();
  }
  ~ScriptedServer() { m_server->Shutdown(); }

  DataClient connect(bool packedReads = true) const {
    dataservice::ClientOptions options;
    options.target = fmt::format("127.0.0.1:{}", m_port);
    options.insecure = true;
    options.timeoutSeconds = 10.0;
    options.packedReads = packedReads;
    return DataClient::connect(options).value();
  }

 private:
  class Reactor : public grpc::ServerGenericBidiReactor {
   public:
    explicit Reactor(const std::vector<std::string>& messages) : m_messages(messages) {
      StartRead(&m_request);
    }
    void OnReadDone(bool) override { next(); }
    void OnWriteDone(bool ok) override {
      if (!ok) {
        Finish(grpc::Status::CANCELLED);
        return;
      }
      next();
    }
    void OnDone() override { delete this; }

   private:
    void next() {
      if (m_sent == m_messages.size()) {
        Finish(grpc::Status::OK);
        return;
      }
      grpc::Slice slice(m_messages[m_sent++]);
      m_reply = grpc::ByteBuffer(&slice, 1);
      StartWrite(&m_reply);
    }

    const std::vector<std::string>& m_messages;
    grpc::ByteBuffer m_request;
    grpc::ByteBuffer m_reply;
    std::size_t m_sent = 0;
  };

  class Service : public grpc::CallbackGenericService {
   public:
    explicit Service(std::vector<std::string> messages) : m_messages(std::move(messages)) {}
    grpc::ServerGenericBidiReactor* CreateReactor(grpc::GenericCallbackServerContext*) override {
      return new Reactor(m_messages);
    }

   private:
    std::vector<std::string> m_messages;
  };

  Service m_service;
  int m_port = 0;
  std::unique_ptr<grpc::Server> m_server;
};

v1::ReadChunk header(std::uint32_t slab, std::uint64_t slabBytes, std::uint64_t offset) {
  v1::ReadChunk chunk;
  chunk.set_slab_index(slab);
  chunk.set_dtype(v1::UINT8);
  chunk.add_shape(slabBytes);
  chunk.set_slab_bytes(slabBytes);
  chunk.set_offset(offset);
  return chunk;
}

std::string chunk(std::uint32_t slab, std::uint64_t slabBytes, std::uint64_t offset,
                  const std::string& data) {
  v1::ReadChunk message = header(slab, slabBytes, offset);
  message.set_data(data);
  return message.SerializeAsString();
}

Result<std::vector<dataservice::TypedArray>> readFrom(const ScriptedServer& server, int slabs) {
  std::vector<Hyperslab> request;
  for (int i = 0; i < slabs; ++i) {
    request.push_back(Hyperslab::whole(fmt::format("/s{}", i)));
  }
  return server.connect().read("any.h5", request);
}

std::string asString(const std::vector<std::byte>& bytes) {
  return {reinterpret_cast<const char*>(bytes.data()), bytes.size()};
}

TEST_CASE("Read chunks are taken off the wire as protobuf defines them",
          "[dataservice][integration]") {
  SECTION("the server's order: header fields, then the data") {
    ScriptedServer server({chunk(0, 6, 0, "abc"), chunk(0, 6, 3, "def"), chunk(1, 2, 0, "gh")});
    auto arrays = readFrom(server, 2);
    INFO(arrays.status().message());
    REQUIRE(arrays.isOk());
    CHECK(asString((*arrays)[0].bytes) == "abcdef");
    CHECK((*arrays)[0].dtype == dataservice::DataType::kUInt8);
    CHECK((*arrays)[0].shape == std::vector<std::uint64_t>{6});
    CHECK(asString((*arrays)[1].bytes) == "gh");
  }

  SECTION("the data before the other fields, unknown fields, shape unpacked") {
    v1::ReadChunk data;
    data.set_data("abcdef");
    // Two serialized messages one after the other parse as their merge.
    std::string dataFirst = data.SerializeAsString() + header(0, 6, 0).SerializeAsString();
    // Fields this client does not know, after the data: 15 = 7 (varint),
    // 16 = "ignored" (length-delimited), 17 (fixed32), 18 (fixed64).
    const std::string withUnknown = chunk(0, 6, 0, "abcdef") +
                                    std::string("\x78\x07\x82\x01\x07ignored", 12) +
                                    std::string("\x8d\x01\x01\x02\x03\x04", 6) +
                                    std::string("\x91\x01\x01\x02\x03\x04\x05\x06\x07\x08", 10);
    // slab_index 0, dtype UINT8 (2), shape 6 as an unpacked varint, slab_bytes
    // 6, offset 0, data "abcdef".
    const std::string unpacked(
        "\x08\x00\x10\x02\x18\x06\x20\x06\x28\x00\x32\x06"
        "abcdef",
        18);
    // The data given twice: the last one counts.
    v1::ReadChunk first;
    first.set_data("xxxxxx");
    std::string twice = first.SerializeAsString() + chunk(0, 6, 0, "abcdef");
    for (const std::string& message : {dataFirst, withUnknown, unpacked, twice}) {
      ScriptedServer server({message});
      auto arrays = readFrom(server, 1);
      INFO(arrays.status().message());
      REQUIRE(arrays.isOk());
      CHECK(asString((*arrays)[0].bytes) == "abcdef");
      CHECK((*arrays)[0].shape == std::vector<std::uint64_t>{6});
    }
  }

  SECTION("chunks that do not fit their slab, and broken messages, end the call") {
    const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
        {{chunk(0, 6, 3, "def")}, "out of order"},
        {{chunk(0, 6, 0, "abcdefg")}, "too long"},
        {{chunk(1, 6, 0, "abcdef")}, "chunk for slab 1 of 1"},
        {{chunk(0, 5, 0, "abcde") + header(0, 6, 0).SerializeAsString()}, "announces"},
        {{std::string("\x32\x10", 2) + "abc"}, "malformed chunk"},  // 16 bytes announced, 3 sent
        {{std::string("\x08\xff\xff", 3)}, "malformed chunk"},
        {{chunk(0, 6, 0, "abcdef") + std::string("\x7b", 1)}, "malformed chunk"},  // a group
        {{chunk(0, 6, 0, "abc")}, "ended after 3 of 6 bytes"}};
    for (const auto& [messages, expected] : cases) {
      ScriptedServer server(messages);
      auto arrays = readFrom(server, 1);
      CHECK(arrays.status().code() == StatusCode::kInternal);
      CHECK_THAT(arrays.status().message(), Catch::Contains(expected));
    }
  }
}

// A packed chunk of int32 pairs, as the server sends it: the fields, then
// the data (or, with `dataFirst`, the data before them).
std::string packedPairs(const std::vector<std::int32_t>& values, std::uint64_t slabBytes,
                        std::uint64_t offset, bool dataFirst = false) {
  const std::size_t rawBytes = values.size() * sizeof(std::int32_t);
  std::vector<std::byte> packed(dataservice::kMaxChunkBytes);
  const std::size_t size = dataservice::packChunk(dataservice::DataType::kInt32, 2,
                                                  reinterpret_cast<const std::byte*>(values.data()),
                                                  rawBytes, packed.data(), packed.size());
  REQUIRE(size > 0);
  v1::ReadChunk fields;
  fields.set_slab_index(0);
  fields.set_dtype(v1::INT32);
  fields.add_shape(slabBytes / 8);
  fields.add_shape(2);
  fields.set_slab_bytes(slabBytes);
  fields.set_offset(offset);
  fields.set_encoding(v1::CHUNK_ENCODING_PACKED);
  fields.set_decoded_bytes(rawBytes);
  v1::ReadChunk data;
  data.set_data(std::string(reinterpret_cast<const char*>(packed.data()), size));
  return dataFirst ? data.SerializeAsString() + fields.SerializeAsString()
                   : fields.SerializeAsString() + data.SerializeAsString();
}

// Sorted pairs of nearby particles, as a lattice's bond list.
std::vector<std::int32_t> nearbyPairs(std::size_t bonds) {
  std::vector<std::int32_t> values;
  for (std::size_t b = 0; b < bonds; ++b) {
    values.push_back(static_cast<std::int32_t>(b / 3));
    values.push_back(static_cast<std::int32_t>(b / 3 + 1 + (b % 3) * 40));
  }
  return values;
}

TEST_CASE("Packed chunks are unpacked in place, and a malformed one ends the call",
          "[dataservice][integration]") {
  // 1 MiB of pairs packed (about 200 KiB, more than one receive buffer),
  // then a small packed chunk with its data first, then a raw one.
  const std::size_t bonds = (dataservice::kMaxChunkBytes / 8) + 1000 + 10;
  const auto values = nearbyPairs(bonds);
  const std::uint64_t slabBytes = bonds * 8;
  const std::vector<std::int32_t> first(values.begin(),
                                        values.begin() + dataservice::kMaxChunkBytes / 4);
  const std::vector<std::int32_t> second(values.begin() + dataservice::kMaxChunkBytes / 4,
                                         values.end() - 20);
  const std::vector<std::int32_t> third(values.end() - 20, values.end());
  v1::ReadChunk rawThird;
  rawThird.set_slab_index(0);
  rawThird.set_dtype(v1::INT32);
  rawThird.add_shape(bonds);
  rawThird.add_shape(2);
  rawThird.set_slab_bytes(slabBytes);
  rawThird.set_offset(slabBytes - 80);
  rawThird.set_decoded_bytes(80);
  rawThird.set_data(std::string(reinterpret_cast<const char*>(third.data()), 80));

  SECTION("packed and raw chunks of one slab, in either field order") {
    ScriptedServer server({packedPairs(first, slabBytes, 0),
                           packedPairs(second, slabBytes, dataservice::kMaxChunkBytes, true),
                           rawThird.SerializeAsString()});
    DataClient client = server.connect();
    auto arrays = client.read("any.h5", {Hyperslab::whole("/bonds/pairs")});
    INFO(arrays.status().message());
    REQUIRE(arrays.isOk());
    auto received = (*arrays)[0].values<std::int32_t>();
    REQUIRE(received.isOk());
    CHECK(*received == values);
    CHECK((*arrays)[0].shape == std::vector<std::uint64_t>{bonds, 2});
    CHECK(client.readWireBytes() < slabBytes / 4);
  }

  SECTION("a packed chunk that does not say what it holds, or lies, ends the call") {
    const auto withFields = [&](const std::function<void(v1::ReadChunk&)>& change) {
      v1::ReadChunk message;
      message.ParseFromString(packedPairs(first, slabBytes, 0));
      change(message);
      return message.SerializeAsString();
    };
    const std::vector<std::pair<std::string, std::string>> cases = {
        {withFields([](v1::ReadChunk& m) { m.set_encoding(static_cast<v1::ChunkEncoding>(9)); }),
         "unknown encoding 9"},
        {withFields([](v1::ReadChunk& m) { m.clear_decoded_bytes(); }), "says it holds 0"},
        {withFields([](v1::ReadChunk& m) { m.set_decoded_bytes(2 * dataservice::kMaxChunkBytes); }),
         "at most 1048576"},
        {withFields([](v1::ReadChunk& m) { m.set_decoded_bytes(m.data().size()); }),
         "more than it takes"},
        {withFields([](v1::ReadChunk& m) { (*m.mutable_data())[0] = 0; }), "0 columns"},
        {withFields([](v1::ReadChunk& m) { m.mutable_data()->pop_back(); }), "where its header"},
        {withFields([](v1::ReadChunk& m) {
           m.set_encoding(v1::CHUNK_ENCODING_RAW);
           m.set_decoded_bytes(m.data().size() + 1);
         }),
         "says it holds"},
    };
    for (const auto& [message, expected] : cases) {
      ScriptedServer server({message});
      auto arrays = server.connect().read("any.h5", {Hyperslab::whole("/bonds/pairs")});
      CHECK(arrays.status().code() == StatusCode::kInternal);
      CHECK_THAT(arrays.status().message(), Catch::Contains(expected));
    }
    // A packed chunk to a client that asked for raw ones.
    ScriptedServer server({packedPairs(first, slabBytes, 0)});
    auto unasked =
        server.connect(/*packedReads=*/false).read("any.h5", {Hyperslab::whole("/bonds/pairs")});
    CHECK(unasked.status().code() == StatusCode::kInternal);
    CHECK_THAT(unasked.status().message(), Catch::Contains("did not accept"));
  }
}

TEST_CASE("Integer slabs travel packed and arrive as they were, reals as they are",
          "[dataservice][integration]") {
  auto server = startServer(baseConfig());
  auto packedOptions = clientOptions(*server);
  auto rawOptions = packedOptions;
  rawOptions.packedReads = false;
  auto packed = connect(packedOptions);
  auto raw = connect(rawOptions);
  const std::vector<Hyperslab> slabs = {Hyperslab::whole("/bonds/pairs"),
                                        Hyperslab::whole("/steps/000002/bond_state"),
                                        Hyperslab::whole("/steps/000002/positions"),
                                        {"/bonds/pairs", {5, 0}, {40, 2}},
                                        {"/bonds/pairs", {0, 1}, {60, 1}}};
  auto a = packed.read("run.h5", slabs);
  auto b = raw.read("run.h5", slabs);
  INFO(a.status().message() << " / " << b.status().message());
  REQUIRE(a.isOk());
  REQUIRE(b.isOk());
  std::uint64_t bytes = 0;
  for (std::size_t i = 0; i < slabs.size(); ++i) {
    CHECK((*a)[i].dtype == (*b)[i].dtype);
    CHECK((*a)[i].shape == (*b)[i].shape);
    CHECK((*a)[i].bytes == (*b)[i].bytes);
    bytes += (*b)[i].bytes.size();
  }
  CHECK(raw.readWireBytes() == bytes);
  const std::uint64_t positions = (*b)[2].bytes.size();
  // The pairs and states packed to a fraction; the positions as they are.
  CHECK(packed.readWireBytes() < positions + (bytes - positions) / 3);
  CHECK(packed.readWireBytes() > positions);
  requireServerHealthy(*server);
}

TEST_CASE("A Read can be started before its buffers exist and checked chunk by chunk",
          "[dataservice][integration]") {
  auto server = startServer(baseConfig());
  auto client = connect(clientOptions(*server));
  const std::vector<Hyperslab> ramp = {Hyperslab::whole("/ramp")};
  std::vector<double> values;

  SECTION("every chunk is announced once its bytes are in place, in order") {
    auto pending = client.startRead("big.h5", ramp);
    values.resize(std::size_t{2} << 20);  // allocated while the server reads
    std::uint64_t expectedOffset = 0;
    int chunks = 0;
    const Status status = pending.receive(
        [&](const DataClient::SlabHeader& slab) -> Result<std::byte*> {
          REQUIRE(slab.bytes == values.size() * sizeof(double));
          return reinterpret_cast<std::byte*>(values.data());
        },
        [&](std::size_t slab, std::uint64_t offset, std::uint64_t bytes) -> Status {
          CHECK(slab == 0);
          CHECK(offset == expectedOffset);
          CHECK(bytes <= dataservice::kMaxChunkBytes);
          const auto first = static_cast<std::size_t>(offset / sizeof(double));
          CHECK(values[first] == 0.5 * static_cast<double>(first));
          expectedOffset += bytes;
          ++chunks;
          return Status::ok();
        });
    INFO(status.message());
    REQUIRE(status.isOk());
    CHECK(chunks == 16);
    CHECK(expectedOffset == values.size() * sizeof(double));
    CHECK(values.back() == 0.5 * static_cast<double>(values.size() - 1));
    CHECK(pending
              .receive([](const DataClient::SlabHeader&) -> Result<std::byte*> {
                return internalError("not called");
              })
              .code() == StatusCode::kInternal);
  }

  SECTION("an error from the check ends the call with that error") {
    values.resize(std::size_t{2} << 20);
    int chunks = 0;
    const Status status =
        client.startRead("big.h5", ramp)
            .receive(
                [&](const DataClient::SlabHeader&) -> Result<std::byte*> {
                  return reinterpret_cast<std::byte*>(values.data());
                },
                [&](std::size_t, std::uint64_t, std::uint64_t) -> Status {
                  return ++chunks == 2 ? failedPrecondition("bad values") : Status::ok();
                });
    CHECK(status.code() == StatusCode::kFailedPrecondition);
    CHECK(status.message() == "bad values");
    CHECK(chunks == 2);
  }

  SECTION("a Read dropped before it is received is cancelled") {
    for (int i = 0; i < 3; ++i) {
      auto pending = client.startRead("big.h5", ramp);
    }
  }
  requireServerHealthy(*server);
}

TEST_CASE("A bond list with an index out of range is refused, naming the bond",
          "[dataservice][integration]") {
  TempDir root;
  const SampleData sample = writeSampleFile(root.file("run.h5"));
  const auto lastBond = static_cast<std::uint64_t>(sample.lattice.bondCount() - 1);
  {
    std::lock_guard lock(dataservice::hdf5Mutex());
    setInt32Elements(root.file("run.h5"), "/bonds/pairs", {3, -1}, 2 * lastBond);
  }
  auto config = baseConfig();
  config.dataRoot = root.path().string();
  auto server = startServer(config);
  auto client = connect(clientOptions(*server));
  // Read with the first step, or asked for with the description.
  const bool prefetch = GENERATE(false, true);
  INFO("bond list prefetched: " << prefetch);
  auto file = dataservice::RemoteDemFile::open(client, "run.h5", {.prefetchBondList = prefetch});
  INFO(file.status().message());
  REQUIRE(file.isOk());
  auto step = file->readStep(1);
  CHECK(step.status().code() == StatusCode::kFailedPrecondition);
  CHECK_THAT(step.status().message(),
             Catch::Contains(fmt::format("bond {} joins particles 3 and -1", lastBond)));
  CHECK_FALSE(file->bondsLoaded());
  REQUIRE(waitUntil([&] { return server->activeStreams() == 0; }));
}

TEST_CASE("A bond list asked for with the description is the one read with a step",
          "[dataservice][integration]") {
  const SampleRoot& sample = sampleRoot();
  auto server = startServer(baseConfig());
  auto client = connect(clientOptions(*server));
  auto plain = dataservice::RemoteDemFile::open(client, "run.h5");
  auto early = dataservice::RemoteDemFile::open(client, "run.h5", {.prefetchBondList = true});
  REQUIRE(plain.isOk());
  REQUIRE(early.isOk());
  CHECK_FALSE(early->bondsLoaded());  // taken on first use
  for (const int step : {2, 0}) {
    auto a = plain->readStep(step);
    auto b = early->readStep(step);
    REQUIRE(a.isOk());
    REQUIRE(b.isOk());
    CHECK(a->positions == b->positions);
    CHECK(a->bondState == b->bondState);
  }
  auto bonds = early->bonds();
  REQUIRE(bonds.isOk());
  CHECK(**bonds == sample.sample3d.lattice.bonds);
  // bonds() alone takes it too.
  auto listOnly = dataservice::RemoteDemFile::open(client, "run.h5", {.prefetchBondList = true});
  REQUIRE(listOnly.isOk());
  auto again = listOnly->bonds();
  REQUIRE(again.isOk());
  CHECK(**again == sample.sample3d.lattice.bonds);
  // Handed over: moved out when nobody shares it, copied when someone does;
  // later steps do not read it again, and it is not handed over twice.
  for (const bool shared : {false, true}) {
    INFO("the list shared: " << shared);
    auto handed = dataservice::RemoteDemFile::open(client, "run.h5", {.prefetchBondList = true});
    REQUIRE(handed.isOk());
    std::shared_ptr<const std::vector<dem::Bond>> holder;
    if (shared) {
      holder = handed->bonds().value();
    }
    auto taken = handed->takeBonds();
    REQUIRE(taken.isOk());
    CHECK(*taken == sample.sample3d.lattice.bonds);
    if (shared) {
      CHECK(*holder == sample.sample3d.lattice.bonds);
    }
    CHECK(handed->bondsLoaded());
    auto later = handed->readStep(2);
    REQUIRE(later.isOk());
    CHECK(later->positions == plain->readStep(2)->positions);
    CHECK(handed->takeBonds().status().code() == StatusCode::kFailedPrecondition);
    CHECK(handed->bonds().status().code() == StatusCode::kFailedPrecondition);
  }

  // A file dropped before its first step cancels the list's stream.
  {
    auto dropped = dataservice::RemoteDemFile::open(client, "run.h5", {.prefetchBondList = true});
    REQUIRE(dropped.isOk());
  }
  REQUIRE(waitUntil([&] { return server->activeStreams() == 0; }));
  // A file that is not there: the description's answer, as without.
  auto missing = dataservice::RemoteDemFile::open(client, "none.h5", {.prefetchBondList = true});
  CHECK(missing.status().code() == StatusCode::kNotFound);
  CHECK(missing.status().message() ==
        dataservice::RemoteDemFile::open(client, "none.h5").status().message());
  REQUIRE(waitUntil([&] { return server->activeStreams() == 0; }));
  requireServerHealthy(*server);
}

TEST_CASE("Radii asked for with the bond list come in its Read: a first view takes two Reads",
          "[dataservice][integration]") {
  const SampleRoot& sample = sampleRoot();
  TempDir logDir;
  auto config = baseConfig();
  config.accessLog = logDir.file("access.log");
  auto server = startServer(config);
  auto client = connect(clientOptions(*server));
  auto view = dataservice::RemoteDemFile::open(client, "run.h5",
                                               {.prefetchBondList = true, .prefetchRadii = true});
  REQUIRE(view.isOk());
  // As a step source opens: the list, the radii, then a step.
  auto taken = view->takeBonds();
  REQUIRE(taken.isOk());
  CHECK(*taken == sample.sample3d.lattice.bonds);
  auto radii = view->radii();
  REQUIRE(radii.isOk());
  CHECK(*radii == sample.sample3d.lattice.radius);
  auto step = view->readStep(1);
  REQUIRE(step.isOk());
  CHECK(step->positions == sample.sample3d.steps[1].positions);
  auto readsLogged = [&] {
    std::ifstream in(config.accessLog);
    const auto logged = lines(std::string(std::istreambuf_iterator<char>(in), {}));
    return std::count_if(logged.begin(), logged.end(), [](const std::string& line) {
      return line.find("method=Read ") != std::string::npos;
    });
  };
  REQUIRE(waitUntil([&] { return readsLogged() >= 2; }));
  CHECK(readsLogged() == 2);  // the list with the radii, and the step
  // Handed over once: asked for again, they are read.
  auto again = view->radii();
  REQUIRE(again.isOk());
  CHECK(*again == sample.sample3d.lattice.radius);
  REQUIRE(waitUntil([&] { return readsLogged() == 3; }));
  // Without prefetchRadii (crackvis bench transfer's first view) the list's
  // Read carries the list alone: the radii take a Read of their own.
  auto listOnly = dataservice::RemoteDemFile::open(client, "run.h5", {.prefetchBondList = true});
  REQUIRE(listOnly.isOk());
  REQUIRE(listOnly->takeBonds().isOk());
  auto own = listOnly->radii();
  REQUIRE(own.isOk());
  CHECK(*own == sample.sample3d.lattice.radius);
  REQUIRE(waitUntil([&] { return readsLogged() >= 5; }));
  CHECK(readsLogged() == 5);

  // A refused prefetch leaves both to be read when asked for.
  config.limits.maxConcurrentStreams = 1;
  config.accessLog = logDir.file("narrow.log");
  auto narrow = startServer(config);
  auto narrowClient = connect(clientOptions(*narrow));
  auto stub = rawStub(*narrow);
  HeldFetch holder(*stub);
  auto refused = dataservice::RemoteDemFile::open(
      narrowClient, "run.h5", {.prefetchBondList = true, .prefetchRadii = true});
  REQUIRE(refused.isOk());
  // The open answers on the Describe; the prefetch's Read is sent after it.
  // The slot is held until the server has refused that Read (CI once freed
  // it first, and the prefetch was served).
  auto prefetchRefused = [&] {
    std::ifstream narrowLog(config.accessLog);
    const auto logged = lines(std::string(std::istreambuf_iterator<char>(narrowLog), {}));
    return std::any_of(logged.begin(), logged.end(), [](const std::string& line) {
      return line.find("method=Read ") != std::string::npos &&
             line.find("status=RESOURCE_EXHAUSTED") != std::string::npos;
    });
  };
  REQUIRE(waitUntil(prefetchRefused));
  holder.cancel();
  holder.finish();
  REQUIRE(waitUntil([&] { return narrow->activeStreams() == 0; }));
  auto late = refused->radii();
  REQUIRE(late.isOk());
  CHECK(*late == sample.sample3d.lattice.radius);
  requireServerHealthy(*server);
  requireServerHealthy(*narrow);
}

TEST_CASE("A prefetched bond list needs one stream at a time, and a refused one is read again",
          "[dataservice][integration]") {
  const SampleRoot& sample = sampleRoot();
  auto config = baseConfig();
  config.limits.maxConcurrentStreams = 1;
  auto server = startServer(config);
  auto client = connect(clientOptions(*server));
  auto view = dataservice::RemoteDemFile::open(client, "run.h5", {.prefetchBondList = true});
  REQUIRE(view.isOk());
  // The step's Read, sent while the list streams, is refused and asked for
  // again once the list is in (its slot free before the client has its
  // status).
  auto step = view->readStep(1);
  INFO(step.status().message());
  REQUIRE(step.isOk());
  CHECK(step->positions == sample.sample3d.steps[1].positions);

  // Another stream holds the only slot while the file is opened: the
  // prefetch is refused, the step still reads, and the list comes when
  // asked for.
  auto stub = rawStub(*server);
  HeldFetch holder(*stub);
  auto refused = dataservice::RemoteDemFile::open(client, "run.h5", {.prefetchBondList = true});
  REQUIRE(refused.isOk());  // the Describe is no stream
  holder.cancel();
  holder.finish();
  REQUIRE(waitUntil([&] { return server->activeStreams() == 0; }));
  auto again = refused->readStep(2);
  REQUIRE(again.isOk());
  CHECK(again->bondState == sample.sample3d.steps[2].bondState);
  // The refused list is read when asked for.
  auto list = refused->bonds();
  REQUIRE(list.isOk());
  CHECK(**list == sample.sample3d.lattice.bonds);
  requireServerHealthy(*server);
}

// Whether this process holds `path` open (the catalogue's kept files).
bool heldOpen(const fs::path& path) {
  for (const auto& entry : fs::directory_iterator("/proc/self/fd")) {
    std::error_code error;
    if (fs::read_symlink(entry.path(), error) == path) {
      return true;
    }
  }
  return false;
}

TEST_CASE("Files kept open between calls are read afresh once changed", "[dataservice]") {
  using namespace crackvis::dataservice;
  TempDir root;
  const fs::path path = fs::canonical(root.path()) / "run.h5";
  const fs::path next = fs::canonical(root.path()) / "next.h5";
  {
    std::lock_guard lock(hdf5Mutex());
    writeSample(path.string(), makeSample(3, 3));
    writeSample(next.string(), makeSample(3, 5));
  }
  Catalogue catalogue(DataRoot::open(root.path().string()).value());
  auto describe = [&]() -> Result<FileDescription> {
    auto file = catalogue.root().resolveFile("run.h5");
    REQUIRE(file.isOk());
    return catalogue.describe(*file);
  };
  // Only a file unchanged for two seconds is kept open.
  REQUIRE(describe().value().steps.size() == 3);
  CHECK_FALSE(heldOpen(path));
  std::this_thread::sleep_for(std::chrono::milliseconds(2100));
  REQUIRE(describe().value().steps.size() == 3);
  CHECK(heldOpen(path));
  // Closed once idle, so that a writer may open it.
  catalogue.closeIdleFiles();
  CHECK(heldOpen(path));
  std::this_thread::sleep_for(std::chrono::milliseconds(2100));
  catalogue.closeIdleFiles();
  CHECK_FALSE(heldOpen(path));
  REQUIRE(describe().value().steps.size() == 3);
  CHECK(heldOpen(path));

  // Changed in place with its size and modification time kept: the format
  // attribute's "crackvis-dem" becomes "crackvis-DEM", written as raw bytes
  // (HDF5 would refuse to write a file this process has open read-only).
  const auto modified = fs::last_write_time(path);
  const auto size = fs::file_size(path);
  {
    std::fstream stream(path, std::ios::in | std::ios::out | std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(stream)), {});
    const auto position = bytes.find("crackvis-dem");
    REQUIRE(position != std::string::npos);
    stream.seekp(static_cast<std::streamoff>(position));
    stream.write("crackvis-DEM", 12);
  }
  fs::last_write_time(path, modified);
  REQUIRE(fs::file_size(path) == size);
  CHECK(describe().value().format == "crackvis-DEM");

  // Replaced by another file.
  fs::rename(next, path);
  CHECK(describe().value().steps.size() == 5);

  // Cut short.
  truncateFile(path.string(), 0.5);
  CHECK(describe().status().code() == StatusCode::kFailedPrecondition);
  CHECK_FALSE(heldOpen(path));
}

}  // namespace
}  // namespace crackvis::testing
