// The data service under hostile but authenticated use (issue 13 points 1,
// 4 and 9): fast token checks, throttled sign-in failures, the handler
// boundary, folder answers that are no existence oracle, per-user stream
// caps, refused NULs, capped echoes, a busy port, idle raw TLS
// connections and connection caps per address; and user B's Read latency while user A describes a
// hostile file. Each through a real server on loopback.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <thread>
#include <vector>

#include <arpa/inet.h>
#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <grpcpp/grpcpp.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include "crackvis/v1/data.grpc.pb.h"
#include "service_fixture.hpp"
#include "support/process.hpp"
#include <crackvis/common/base64.hpp>
#include <crackvis/rpc/grpc_status.hpp>
#include <crackvis/rpc_server/access_log.hpp>
#include <crackvis/rpc_server/call.hpp>
#include <crackvis/rpc_server/credentials.hpp>
#include <crackvis/rpc_server/server.hpp>

namespace crackvis::testing {
namespace {

namespace v1 = crackvis::v1;
using dataservice::Hyperslab;

double secondsOf(const std::function<void()>& work) {
  const auto start = std::chrono::steady_clock::now();
  work();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Connects to `port` on loopback, sends nothing, and waits (5 s at most)
// for the server to close the connection: the seconds it took, or 1e9.
double secondsUntilClosed(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  REQUIRE(fd >= 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  REQUIRE(::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0);
  bool closed = false;
  const double waited = secondsOf([&] {
    char buffer[256];
    for (int round = 0; round < 50 && !closed; ++round) {
      pollfd ready{fd, POLLIN, 0};
      if (::poll(&ready, 1, 100) > 0) {
        closed = ::recv(fd, buffer, sizeof(buffer), 0) <= 0;
      }
    }
  });
  ::close(fd);
  return closed ? waited : 1e9;
}

TEST_CASE("Tokens are checked with one SHA-256, old PBKDF2 token hashes still work",
          "[dataservice][rpc]") {
  const std::string hash = rpc::hashToken("random-token").value();
  CHECK(hash.rfind("sha256$", 0) == 0);
  CHECK(rpc::verifySecret("random-token", hash));
  CHECK_FALSE(rpc::verifySecret("random-token ", hash));
  CHECK_FALSE(rpc::verifySecret("random-token", "sha256$not base64"));
  rpc::Authenticator authenticator(
      {{"fast", hash, "", "", {"*"}},
       {"old", rpc::hashSecret("old-token", rpc::kDefaultHashIterations).value(), "", "", {"*"}}});
  CHECK(authenticator.authenticate("Bearer random-token", "", "ipv4:10.0.0.1:1").value().name ==
        "fast");
  CHECK(authenticator.authenticate("Bearer old-token", "", "ipv4:10.0.0.1:2").value().name ==
        "old");
  // A fresh token check costs microseconds, not a PBKDF2 (tens of ms).
  rpc::Authenticator fastOnly({{"fast", hash, "", "", {"*"}}});
  const double fast = secondsOf([&] {
    for (int i = 0; i < 20; ++i) {
      CHECK(fastOnly
                .authenticate(fmt::format("Bearer wrong-{}", i), "",
                              fmt::format("ipv4:10.0.1.{}:1", i))
                .status()
                .code() == StatusCode::kUnauthenticated);
    }
  });
  CHECK(fast < 0.05);
}

TEST_CASE("Unknown and known user names cost the same", "[dataservice][rpc]") {
  rpc::Authenticator authenticator(
      {{"bob", "", rpc::hashSecret("pw", rpc::kDefaultHashIterations).value(), "", {"bob"}}});
  // base64 of "bob:wrong" and of "nobody:wrong".
  const std::string knownName = "Basic Ym9iOndyb25n";
  const std::string unknownName = "Basic bm9ib2R5Ondyb25n";
  double known = 1e9;
  double unknown = 1e9;
  for (int i = 0; i < 3; ++i) {
    known = std::min(
        known, secondsOf([&] {
          CHECK_FALSE(authenticator.authenticate(knownName, "", fmt::format("ipv4:a{}:1", i)));
        }));
    unknown = std::min(
        unknown, secondsOf([&] {
          CHECK_FALSE(authenticator.authenticate(unknownName, "", fmt::format("ipv4:b{}:1", i)));
        }));
  }
  INFO("known " << known << " s, unknown " << unknown << " s");
  CHECK(unknown > 0.5 * known);
  CHECK(known > 0.5 * unknown);
}

TEST_CASE(
    "Failed sign-ins are throttled per claimed name and address, a valid credential gets "
    "through, through the real service",
    "[dataservice][integration]") {
  auto config = baseConfig();
  config.users = {{"bob",
                   rpc::hashToken("bob's token").value(),
                   rpc::hashSecret("bob's password", 1000).value(),
                   "",
                   {"bob"}},
                  {"alice", rpc::hashToken("alice's token").value(), "", "", {"*"}},
                  {"carol", "", rpc::hashSecret("carol's password", 1000).value(), "", {"*"}}};
  auto server = startServer(config);
  auto withPassword = [&](const std::string& user, const std::string& password) {
    auto options = clientOptions(*server);
    options.user = user;
    options.password = password;
    return connect(options);
  };
  auto withToken = [&](const std::string& token) {
    auto options = clientOptions(*server);
    options.token = token;
    return connect(options);
  };
  // Everyone here calls from 127.0.0.1, as users behind one NAT or proxy do.
  // 16 callers with bad tokens: then wrong tokens are refused as throttled,
  // and a user with a valid token is served all the same.
  for (int i = 0; i < 16; ++i) {
    const StatusCode code =
        withToken(fmt::format("guess-{}", i)).describe("bob/b.h5").status().code();
    CHECK(code == (i < rpc::kMaxFailuresPerIdentity ? StatusCode::kUnauthenticated
                                                    : StatusCode::kResourceExhausted));
  }
  CHECK(withToken("alice's token").describe("bob/b.h5").isOk());
  // A name guessed at from this address is refused before hashing, even with
  // its right password now; other names and bob's token are not held up.
  auto carol = withPassword("carol", "carol's password");
  REQUIRE(carol.describe("bob/b.h5").isOk());
  for (int i = 0; i < rpc::kMaxFailuresPerIdentity; ++i) {
    CHECK(withPassword("bob", "wrong").describe("bob/b.h5").status().code() ==
          StatusCode::kUnauthenticated);
    CHECK(withPassword("carol", "wrong").describe("bob/b.h5").status().code() ==
          StatusCode::kUnauthenticated);
  }
  const Status throttled = withPassword("bob", "bob's password").describe("bob/b.h5").status();
  CHECK(throttled.code() == StatusCode::kResourceExhausted);
  CHECK_THAT(throttled.message(), Catch::Contains("too many failed sign-ins with user 'bob' from"));
  CHECK(withToken("bob's token").describe("bob/b.h5").isOk());
  // carol's password was verified before the guesses: it still works, from
  // the connection that signed in and from a new one.
  CHECK(carol.describe("bob/b.h5").isOk());
  CHECK(withPassword("carol", "carol's password").describe("bob/b.h5").isOk());
}

TEST_CASE("Password failures from one address are capped across names", "[dataservice][rpc]") {
  // Ten users with cheap hashes (the test's time), each within its own
  // limit of 10 from one address: together they reach the address's cap.
  std::vector<dataservice::UserEntry> users;
  for (int i = 0; i < 10; ++i) {
    users.push_back({fmt::format("user{}", i),
                     "",
                     rpc::hashSecret(fmt::format("password {}", i), 1000).value(),
                     "",
                     {"*"}});
  }
  users.push_back({"dave", "", rpc::hashSecret("dave's password", 1000).value(), "", {"*"}});
  rpc::Authenticator authenticator(users);
  auto basic = [](const std::string& pair) { return "Basic " + base64Encode(pair); };
  static_assert(rpc::kMaxFailuresPerAddress == 10 * rpc::kMaxFailuresPerIdentity);
  for (int i = 0; i < rpc::kMaxFailuresPerAddress; ++i) {
    const std::string guess = fmt::format("user{}:wrong {}", i % 10, i);
    CHECK(authenticator.authenticate(basic(guess), "", "ipv4:192.0.2.1:1").status().code() ==
          StatusCode::kUnauthenticated);
  }
  const Status capped =
      authenticator.authenticate(basic("dave:dave's password"), "", "ipv4:192.0.2.1:2").status();
  CHECK(capped.code() == StatusCode::kResourceExhausted);
  CHECK_THAT(capped.message(), Catch::Contains("too many failed sign-ins from ipv4:192.0.2.1"));
  CHECK(authenticator.authenticate(basic("dave:dave's password"), "", "ipv4:192.0.2.2:5").isOk());
  // Once verified, that credential passes from the capped address too.
  CHECK(authenticator.authenticate(basic("dave:dave's password"), "", "ipv4:192.0.2.1:3").isOk());
}

TEST_CASE("An exception at a handler's boundary fails only that call", "[dataservice][rpc]") {
  rpc::AccessRecord record;
  record.method = "Describe";
  record.file = "a.h5";
  const Status status =
      rpc::guarded("crackvis-test", record, []() -> Status { throw std::runtime_error("boom"); });
  CHECK(status.code() == StatusCode::kInternal);
  CHECK_THAT(status.message(), Catch::Contains("Describe"));
  const Status unknown = rpc::guarded("crackvis-test", record, []() -> Status { throw 42; });
  CHECK(unknown.code() == StatusCode::kInternal);
}

TEST_CASE("CANCELLED and DEADLINE_EXCEEDED stay distinct", "[dataservice][rpc]") {
  CHECK(rpc::fromGrpcStatus(grpc::Status(grpc::StatusCode::CANCELLED, "x"), "Read").code() ==
        StatusCode::kCancelled);
  CHECK(
      rpc::fromGrpcStatus(grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED, "x"), "Read").code() ==
      StatusCode::kDeadlineExceeded);
  CHECK(rpc::fromGrpcStatus(grpc::Status(grpc::StatusCode::UNAVAILABLE, "x"), "Read").code() ==
        StatusCode::kUnavailable);
  CHECK(rpc::toGrpcStatus(cancelled("x")).error_code() == grpc::StatusCode::CANCELLED);
  CHECK(rpc::toGrpcStatus(deadlineExceeded("x")).error_code() ==
        grpc::StatusCode::DEADLINE_EXCEEDED);
  // Through a real call: a deadline that passes is DEADLINE_EXCEEDED.
  auto server = startServer(baseConfig());
  auto stub = rawStub(*server);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now());
  v1::DescribeResponse response;
  v1::DescribeRequest request;
  request.set_file("run.h5");
  const Status late = rpc::fromGrpcStatus(stub->Describe(&context, request, &response), "Describe");
  CHECK(late.code() == StatusCode::kDeadlineExceeded);
}

TEST_CASE("Another user's folder answers as a missing one, no listing names a foreign file",
          "[dataservice][integration]") {
  auto config = baseConfig();
  config.users = {{"alice", rpc::hashToken("alice-token").value(), "", "", {"alice"}}};
  auto server = startServer(config);
  auto options = clientOptions(*server);
  options.token = "alice-token";
  auto alice = connect(options);
  const Status foreign = alice.listFiles("bob").status();
  const Status missing = alice.listFiles("nosuch").status();
  CHECK(foreign.code() == StatusCode::kNotFound);
  CHECK(missing.code() == StatusCode::kNotFound);
  CHECK(foreign.message() == "folder 'bob' not found under the data root");
  CHECK(missing.message() == "folder 'nosuch' not found under the data root");
  // A file in another's folder is not a folder either: same answer.
  CHECK(alice.listFiles("bob/b.h5").status().code() == StatusCode::kNotFound);
  auto own = alice.listFiles("alice");
  REQUIRE(own.isOk());
  std::vector<std::string> names;
  for (const auto& file : *own) {
    names.push_back(file.path);
  }
  // alice/bob-link.h5 -> ../bob/b.h5 is in her folder but leads to bob's file.
  CHECK(names == std::vector<std::string>{"alice/a.h5"});
}

TEST_CASE("NULs, huge names and echoes: refused or capped", "[dataservice][integration]") {
  auto server = startServer(baseConfig());
  auto client = connect(clientOptions(*server));
  const Status nul =
      client.read("run.h5", {Hyperslab::whole(std::string("/bonds/pairs\0/x", 15))}).status();
  CHECK(nul.code() == StatusCode::kInvalidArgument);
  CHECK_THAT(nul.message(), Catch::Contains("NUL"));
  const Status nulFile = client.describe(std::string("run.h5\0.txt", 11)).status();
  CHECK(nulFile.code() == StatusCode::kInvalidArgument);
  CHECK_THAT(nulFile.message(), Catch::Contains("NUL"));
  const std::string longName(3000, 'x');
  const Status missing = client.describe(longName + ".h5").status();
  CHECK(missing.code() == StatusCode::kNotFound);
  CHECK(missing.message().size() < 400);
  CHECK_THAT(missing.message(), Catch::Contains("..."));
  const Status huge = client.describe(std::string(100000, 'y')).status();
  CHECK(huge.code() == StatusCode::kInvalidArgument);
  CHECK(huge.message().size() < 400);
  requireServerHealthy(*server);
}

TEST_CASE("Streams are capped per user beside the server-wide cap", "[dataservice][integration]") {
  auto config = baseConfig();
  config.limits.maxStreamsPerUser = 1;
  config.users = {{"alice", rpc::hashToken("alice-token").value(), "", "", {"*"}},
                  {"bob", rpc::hashToken("bob-token").value(), "", "", {"*"}}};
  auto server = startServer(config);
  auto stub = rawStub(*server);
  v1::FetchRequest request;
  request.set_file("big.h5");
  auto open = [&](grpc::ClientContext& context, const std::string& token) {
    context.AddMetadata("authorization", "Bearer " + token);
    return stub->Fetch(&context, request);
  };
  grpc::ClientContext first;
  auto held = open(first, "alice-token");
  v1::FetchChunk chunk;
  REQUIRE(held->Read(&chunk));  // alice's one stream is open and stays so
  grpc::ClientContext second;
  auto refused = open(second, "alice-token");
  while (refused->Read(&chunk)) {
  }
  const grpc::Status status = refused->Finish();
  CHECK(status.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED);
  CHECK_THAT(status.error_message(), Catch::Contains("per user"));
  grpc::ClientContext other;
  auto bobs = open(other, "bob-token");
  CHECK(bobs->Read(&chunk));  // bob is not held up by alice's cap
  other.TryCancel();
  first.TryCancel();
}

TEST_CASE("A second server on a busy port fails with 'address in use'",
          "[dataservice][integration]") {
  auto server = startServer(baseConfig());
  auto config = baseConfig();
  config.listen = fmt::format("127.0.0.1:{}", server->port());
  auto second = dataservice::DataServer::start(config);
  REQUIRE_FALSE(second.isOk());
  CHECK(second.status().code() == StatusCode::kUnavailable);
  CHECK_THAT(second.status().message(), Catch::Contains("in use"));
  requireServerHealthy(*server);
}

TEST_CASE("Server addresses: IPv6 bracketed, plaintext only on loopback", "[dataservice][rpc]") {
  CHECK(rpc::formatHostPort("::1", 50051) == "[::1]:50051");
  CHECK(rpc::formatHostPort("127.0.0.1", 50051) == "127.0.0.1:50051");
  CHECK(rpc::requireLoopback("localhost:50051", "--data-insecure").isOk());
  const Status remote = rpc::requireLoopback("10.1.2.3:50051", "--data-insecure");
  CHECK(remote.code() == StatusCode::kFailedPrecondition);
  CHECK_THAT(remote.message(), Catch::Contains("--data-insecure"));
}

TEST_CASE("Idle TCP connections to the raw TLS endpoint are closed after the handshake timeout",
          "[dataservice][integration]") {
  auto config = baseConfig();
  config.rawTlsListen = "127.0.0.1:0";
  config.limits.handshakeSeconds = 0.5;
  auto server = startServer(config);
  // Send nothing: the server must close the connection (perhaps after a TLS
  // alert) well before the 30 s socket timeout.
  const double waited = secondsUntilClosed(server->rawTlsPort());
  CHECK(waited < 3.0);
}

}  // namespace
}  // namespace crackvis::testing

namespace crackvis::testing {
namespace {

struct StallFigures {
  double describeSeconds = 0.0;  // one Describe of the hostile file, as A sees it
  double medianReadMs = 0.0;     // user B's Reads meanwhile
  double maxReadMs = 0.0;
  int reads = 0;
};

// User A describes a 600-level chain over and over for `seconds`; user B
// reads one step's positions meanwhile, each Read timed.
StallFigures measureStall(const dataservice::Limits& limits, const TempDir& root,
                          const std::string& hostile, double seconds) {
  auto config = baseConfig();
  config.dataRoot = root.path().string();
  config.limits = limits;
  auto server = startServer(config);
  auto clientA = connect(clientOptions(*server));
  auto clientB = connect(clientOptions(*server));
  StallFigures figures;
  std::atomic<bool> done{false};
  std::thread userA([&] {
    while (!done) {
      // Uncached: every Describe walks (the service holds the answer of an
      // unchanged file otherwise).
      const double took = secondsOf([&] { (void)clientA.describe(hostile, /*uncached=*/true); });
      figures.describeSeconds = std::max(figures.describeSeconds, took);
    }
  });
  std::vector<double> readMs;
  const auto end = std::chrono::steady_clock::now() +
                   std::chrono::milliseconds(static_cast<int>(seconds * 1000));
  std::this_thread::sleep_for(std::chrono::milliseconds(50));  // A is walking
  while (std::chrono::steady_clock::now() < end) {
    readMs.push_back(
        1000.0 * secondsOf([&] {
          REQUIRE(clientB.read("run.h5", {Hyperslab::whole("/steps/000001/positions")}).isOk());
        }));
  }
  done = true;
  userA.join();
  std::sort(readMs.begin(), readMs.end());
  figures.reads = static_cast<int>(readMs.size());
  figures.medianReadMs = readMs[readMs.size() / 2];
  figures.maxReadMs = readMs.back();
  return figures;
}

}  // namespace

namespace {

// A TCP connection to 127.0.0.1:`port` from the loopback address `source`
// (any of 127.0.0.0/8 is this machine's): another client's address.
int connectFrom(const char* source, int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  REQUIRE(fd >= 0);
  sockaddr_in from{};
  from.sin_family = AF_INET;
  REQUIRE(::inet_pton(AF_INET, source, &from.sin_addr) == 1);
  REQUIRE(::bind(fd, reinterpret_cast<sockaddr*>(&from), sizeof(from)) == 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<std::uint16_t>(port));
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  REQUIRE(::connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof(to)) == 0);
  return fd;
}

// Whether the server closes `fd` (EOF or reset) within `seconds`.
bool closedWithin(int fd, double seconds) {
  pollfd ready{fd, POLLIN, 0};
  if (::poll(&ready, 1, static_cast<int>(seconds * 1000)) <= 0) {
    return false;
  }
  char byte = 0;
  return ::recv(fd, &byte, 1, MSG_DONTWAIT) <= 0;
}

}  // namespace

TEST_CASE("Connections past the per-address and total caps are closed before any handshake",
          "[dataservice][integration]") {
  auto config = baseConfig();
  config.limits.maxConnectionsPerAddress = 3;
  config.limits.maxConnections = 4;
  config.limits.handshakeSeconds = 20.0;  // idle connections stay: only the caps close them
  auto server = startServer(config);
  auto describeOn = [](const std::shared_ptr<grpc::Channel>& channel) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
    v1::DescribeRequest request;
    request.set_file("run.h5");
    v1::DescribeResponse response;
    return v1::DataService::NewStub(channel)->Describe(&context, request, &response).ok();
  };
  // A client with a call made, then two idle connections: 3 from 127.0.0.1.
  auto channel = rawChannel(*server);
  REQUIRE(describeOn(channel));
  std::vector<int> idle = {connectFrom("127.0.0.1", server->port()),
                           connectFrom("127.0.0.1", server->port())};
  for (int fd : idle) {
    CHECK_FALSE(closedWithin(fd, 0.3));
  }
  // The fourth from that address is closed at once, long before its
  // handshake time; the address's working client keeps its connection.
  const int fourth = connectFrom("127.0.0.1", server->port());
  CHECK(closedWithin(fourth, 2.0));
  ::close(fourth);
  CHECK(describeOn(channel));
  // Another address still gets in, up to the total of 4.
  const int other = connectFrom("127.0.0.2", server->port());
  CHECK_FALSE(closedWithin(other, 0.3));
  const int pastTotal = connectFrom("127.0.0.3", server->port());
  CHECK(closedWithin(pastTotal, 2.0));
  ::close(pastTotal);
  // Connections that end free their places: a new client from 127.0.0.1
  // connects once the idle ones are gone.
  for (int fd : idle) {
    ::close(fd);
  }
  ::close(other);
  CHECK(waitUntil([&] { return describeOn(rawChannel(*server)); }, 5.0));
}

TEST_CASE("Idle connections to the gRPC port are closed: no handshake, then no call",
          "[dataservice][integration]") {
  auto config = baseConfig();
  config.limits.handshakeSeconds = 0.5;
  config.limits.idleConnectionSeconds = 0.5;
  auto server = startServer(config);
  // A TCP connection that sends nothing is closed after the handshake time.
  CHECK(secondsUntilClosed(server->port()) < 3.0);
  // A connection that made a call and then nothing is sent GOAWAY: the
  // channel goes idle, and its next call reconnects.
  auto channel = rawChannel(*server);
  auto stub = v1::DataService::NewStub(channel);
  auto describe = [&] {
    grpc::ClientContext context;
    v1::DescribeRequest request;
    request.set_file("run.h5");
    v1::DescribeResponse response;
    return stub->Describe(&context, request, &response).ok();
  };
  REQUIRE(describe());
  CHECK(channel->GetState(false) == GRPC_CHANNEL_READY);
  CHECK(waitUntil([&] { return channel->GetState(false) == GRPC_CHANNEL_IDLE; }, 5.0));
  CHECK(describe());
}

TEST_CASE("User B's Reads are not held up by user A describing a hostile file",
          "[dataservice][integration]") {
  TempDir root;
  writeNestedGroups(root.file("deep.h5"), 600);
  writeWideGroups(root.file("wide.h5"), 40'000);
  std::filesystem::copy_file(sampleRoot().file("run.h5"), root.file("run.h5"));
  // Describe's limits lifted (any depth, 10^8 objects, an hour): A's walk
  // of 40,000 groups takes its whole unbounded time.
  dataservice::Limits unbounded;
  unbounded.describe.maxDepth = 100'000;
  unbounded.describe.maxObjects = 100'000'000;
  unbounded.describe.maxTime = std::chrono::milliseconds(3'600'000);
  const StallFigures walk = measureStall(unbounded, root, "wide.h5", 3.0);
  const StallFigures bounded = measureStall(dataservice::Limits{}, root, "deep.h5", 3.0);
  // The figures docs/benchmarks.md quotes (ctest -V -R "User B").
  std::printf(
      "user B's Read while user A describes 40,000 groups, unbounded: Describe %.2f s, Read "
      "median %.1f ms, max %.0f ms (%d reads); a 600-level chain, default limits: Describe "
      "%.3f s, Read median %.1f ms, max %.0f ms (%d reads)\n",
      walk.describeSeconds, walk.medianReadMs, walk.maxReadMs, walk.reads, bounded.describeSeconds,
      bounded.medianReadMs, bounded.maxReadMs, bounded.reads);
  // A's walk runs in an HDF5 worker of its own: B's Reads never wait for a
  // whole walk (before the workers, every one of them did: 1.2-1.4 s).
  CHECK(walk.describeSeconds > 0.3);
  CHECK(walk.maxReadMs < 1000.0 * walk.describeSeconds / 4);
  // With the default limits A is refused at level 65 at once.
  CHECK(bounded.describeSeconds < 0.5);
  CHECK(bounded.maxReadMs < 1000.0 * walk.describeSeconds / 4);
}

}  // namespace crackvis::testing
