// What a client of crackvis-data says when the connection is the problem
// (issue 18, errors that say what to do): nothing listening, a name that
// does not resolve, plaintext against TLS and TLS against plaintext, and
// certificates missing from the built-in default place. Real servers on
// loopback; the CLI as a user runs it (one line on stderr, status 1).
#include <filesystem>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "dataservice/service_fixture.hpp"
#include "support/network.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/common/certificates.hpp>
#include <crackvis/rpc/connection_advice.hpp>

using namespace crackvis;
using namespace crackvis::testing;

namespace {

const std::string kCli = CRACKVIS_CLI;

std::vector<std::string> healthOf(const std::string& address, std::vector<std::string> more = {},
                                  const tls::TlsFiles& tls = clientTls("client")) {
  std::vector<std::string> argv{kCli,     "health", address, "--ca", tls.ca,
                                "--cert", tls.cert, "--key", tls.key};
  argv.insert(argv.end(), more.begin(), more.end());
  return argv;
}

// The one line a failed command printed.
std::string onlyLine(const ProcessResult& result) {
  INFO(result.err);
  CHECK(result.exitCode == 1);
  CHECK(result.out.empty());
  const auto errorLines = lines(result.err);
  REQUIRE(errorLines.size() == 1);
  return errorLines[0];
}

dataservice::ServerConfig insecureConfig() {
  auto config = baseConfig();
  config.insecure = true;
  return config;
}

}  // namespace

TEST_CASE("Nothing listening: the client says which server it wanted and where",
          "[dataservice][integration]") {
  const std::string address = fmt::format("127.0.0.1:{}", closedPort());
  SECTION("crackvis health") {
    CHECK(onlyLine(runProcess(healthOf(address))) ==
          fmt::format("crackvis health: no crackvis-data or crackvis-render at {} (connection "
                      "refused): is it running? see docs/deploy.md",
                      address));
  }
  SECTION("the data client (bench transfer, crackvis-render's sources)") {
    auto options = clientOptions(*startServer(baseConfig()));
    options.target = address;
    auto files = connect(options).listFiles();
    REQUIRE_FALSE(files.isOk());
    CHECK(files.status().code() == StatusCode::kUnavailable);
    CHECK(files.status().message() ==
          fmt::format("no crackvis-data at {} (connection refused): is it running? see "
                      "docs/deploy.md",
                      address));
  }
  SECTION("a host name that does not resolve") {
    const std::string line = onlyLine(runProcess(healthOf("nosuchhost.invalid:50051")));
    CHECK_THAT(line, Catch::StartsWith("crackvis health: no crackvis-data or crackvis-render at "
                                       "nosuchhost.invalid:50051 (cannot resolve "
                                       "'nosuchhost.invalid'"));
    CHECK_THAT(line, Catch::EndsWith("check the host name"));
  }
}

TEST_CASE("Plaintext against TLS and TLS against plaintext are named",
          "[dataservice][integration]") {
  SECTION("--insecure against a server with TLS") {
    auto server = startServer(baseConfig());
    const std::string line = onlyLine(runProcess(healthOf(server->address(), {"--insecure"})));
    CHECK(line == fmt::format("crackvis health: {} speaks TLS, but --insecure asked for "
                              "plaintext: leave --insecure out and give the client certificate "
                              "(--ca, --cert, --key; docs/security.md)",
                              server->address()));
    CHECK_THAT(line, !Catch::Contains("Socket closed"));
  }
  SECTION("TLS against a server on --insecure") {
    auto server = startServer(insecureConfig());
    const std::string line = onlyLine(runProcess(healthOf(server->address())));
    CHECK(line == fmt::format("crackvis health: {} speaks plaintext (a crackvis-data or "
                              "crackvis-render started with --insecure), not TLS: add --insecure "
                              "to reach it",
                              server->address()));
    // gRPC's own handshake log line is not printed beside it.
    CHECK_THAT(line, !Catch::Contains("SSL_ERROR"));
    auto options = clientOptions(*server);
    auto files = connect(options).listFiles();
    CHECK(files.status().message() ==
          fmt::format("{} speaks plaintext (a crackvis-data started with --insecure), not TLS: "
                      "add --insecure to reach it",
                      server->address()));
  }
  SECTION("TLS on both sides with certificates that do not fit") {
    auto server = startServer(baseConfig());
    const auto good = clientTls("client");
    const auto other = clientTls("other-client", "other-ca");
    // This client does not trust the server's CA: its own TLS says why.
    const std::string distrust =
        onlyLine(runProcess(healthOf(server->address(), {}, {other.ca, good.cert, good.key})));
    CHECK(distrust == fmt::format("crackvis health: TLS handshake with {} failed "
                                  "(error:0A000086:SSL routines::certificate verify failed): check "
                                  "--ca, --cert and --key against the server's CA and name "
                                  "(docs/security.md)",
                                  server->address()));
    // The server does not trust this client's certificate: it closes.
    const std::string refused =
        onlyLine(runProcess(healthOf(server->address(), {}, {good.ca, other.cert, other.key})));
    CHECK(refused == fmt::format("crackvis health: TLS handshake with {} failed (the server closed "
                                 "the connection: did it refuse the client certificate?): check "
                                 "--ca, --cert and --key against the server's CA and name "
                                 "(docs/security.md)",
                                 server->address()));
  }
  SECTION("the probe itself") {
    auto tls = startServer(baseConfig());
    auto plain = startServer(insecureConfig());
    CHECK(rpc::probeTransport(tls->address()).transport == rpc::Transport::kTls);
    CHECK(rpc::probeTransport(plain->address()).transport == rpc::Transport::kPlaintext);
    CHECK(rpc::probeTransport(fmt::format("127.0.0.1:{}", closedPort())).transport ==
          rpc::Transport::kRefused);
    CHECK(rpc::probeTransport("unix:/nowhere").transport == rpc::Transport::kUnknown);
  }
}

TEST_CASE("A call's channel is connected first, and given up at once where no TLS server trusts it",
          "[dataservice][integration]") {
  using std::chrono::steady_clock;
  const auto within = [](std::chrono::seconds s) { return std::chrono::system_clock::now() + s; };
  const auto secondsSince = [](steady_clock::time_point start) {
    return std::chrono::duration<double>(steady_clock::now() - start).count();
  };
  SECTION("a server that takes the client: connected") {
    auto server = startServer(baseConfig());
    auto channel = rawChannel(*server);
    rpc::awaitConnection(*channel, server->address(), within(std::chrono::seconds(30)));
    CHECK(channel->GetState(false) == GRPC_CHANNEL_READY);
  }
  SECTION("nothing listening: after the first attempt, not the deadline") {
    const std::string address = fmt::format("127.0.0.1:{}", closedPort());
    auto channel = grpc::CreateChannel(address, grpc::InsecureChannelCredentials());
    const auto start = steady_clock::now();
    rpc::awaitConnection(*channel, address, within(std::chrono::seconds(30)));
    CHECK(channel->GetState(false) != GRPC_CHANNEL_READY);
    CHECK(secondsSince(start) < 3.0);  // its first attempt is refused at once
  }
  SECTION("a TLS server that refuses the certificate: after a second attempt") {
    auto server = startServer(baseConfig());
    const auto good = clientTls("client");
    const auto other = clientTls("other-client", "other-ca");
    auto options = clientOptions(*server);
    options.tls = {good.ca, other.cert, other.key};
    const auto start = steady_clock::now();
    auto files = connect(options).listFiles();  // awaits the connection in its call
    // The probe and a second attempt made at once, not the 5 s bound.
    CHECK(secondsSince(start) < 4.5);
    REQUIRE_FALSE(files.isOk());
    CHECK_THAT(files.status().message(), Catch::Contains("did it refuse the client certificate?"));
  }
}

TEST_CASE("A healthy data service is named as one", "[dataservice][integration]") {
  auto server = startServer(baseConfig());
  const auto result = runProcess(healthOf(server->address()));
  CHECK(result.exitCode == 0);
  CHECK(result.out == fmt::format("{}: SERVING (crackvis-data)\n", server->address()));
  CHECK(connect(clientOptions(*server)).serverProgram() == "crackvis-data");
}

TEST_CASE("Certificates missing from the default place name their flag and key",
          "[dataservice][integration]") {
  // In an empty folder the defaults (certs/generated/...) are missing; the
  // installed copy is looked for in /etc/crackvis/certs.
  const bool installed = std::filesystem::exists(std::string(kInstalledCertificateDir) + "/ca.pem");
  TempDir empty;
  const std::string folder = empty.path().string();
  SECTION("crackvis health") {
    const auto result = runProcess(
        {"env", "-C", folder, kCli, "health", fmt::format("127.0.0.1:{}", closedPort())});
    if (installed) {
      CHECK_THAT(result.err, !Catch::Contains("certs/generated/ca.pem"));
    } else {
      CHECK(onlyLine(result) ==
            "crackvis health: cannot read CA certificate 'certs/generated/ca.pem': No such file or "
            "directory (the default, relative to the current folder; not in /etc/crackvis/certs "
            "either): set it with --ca (docs/security.md)");
    }
  }
  SECTION("crackvis-data") {
    if (!installed) {  // with the installed certificates it would start serving
      const auto result =
          runProcess({"env", "-C", folder, CRACKVIS_DATA, "--root",
                      sampleRoot().root.path().string(), "--listen", "127.0.0.1:0"});
      CHECK(onlyLine(result) ==
            "crackvis-data: cannot read CA certificate 'certs/generated/ca.pem': No such file or "
            "directory (the default, relative to the current folder; not in /etc/crackvis/certs "
            "either): set it with --ca or tls.ca in the configuration file (docs/security.md)");
    }
  }
}
