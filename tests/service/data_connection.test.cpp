// What the render server, the CLI and a data client say when a connection
// goes to the wrong place (issue 18, errors that say what to do): real
// crackvis-data and crackvis-render in this process on loopback, the CLI as
// a user runs it. The advice itself is crackvis/rpc/connection_advice.hpp.
#include <chrono>
#include <fstream>
#include <thread>

#include <catch2/catch.hpp>
#include <grpcpp/grpcpp.h>

#include "crackvis/v1/render.grpc.pb.h"
#include "dataservice/service_fixture.hpp"
#include "service/render_fixture.hpp"
#include "support/network.hpp"
#include "support/process.hpp"
#include <crackvis/dataservice_client/data_client.hpp>
#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/service/render_server.hpp>

using namespace crackvis;
using namespace crackvis::testing;
namespace v1 = crackvis::v1;

namespace {

std::string readText(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// OpenSession on `server` with the "client" certificate and the crack view.
grpc::Status openCrackView(const service::RenderServer& server) {
  const auto tls = clientTls("client");
  grpc::SslCredentialsOptions ssl{readText(tls.ca), readText(tls.key), readText(tls.cert)};
  auto stub = v1::RenderService::NewStub(
      grpc::CreateChannel(fmt::format("localhost:{}", server.port()), grpc::SslCredentials(ssl)));
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  v1::OpenSessionRequest request;
  request.set_pipeline_xml(pipeline::toXml(crackView()));
  v1::OpenSessionResponse response;
  return stub->OpenSession(&context, request, &response);
}

// A render server configured as crackvis-render's flags would leave it:
// data_service's files set one by one, so the messages name --data-*.
service::RenderServerConfig renderTo(const dataservice::DataServer& data,
                                     const std::string& target) {
  auto config = renderConfig(data);
  config.data = service::defaultDataOptions();
  const auto tls = clientTls("crackvis-render");
  config.data.tls.ca = tls.ca;
  config.data.tls.cert = tls.cert;
  config.data.tls.key = tls.key;
  config.data.target = target;
  return config;
}

std::vector<std::string> certificateFlags() {
  const auto tls = clientTls("client");
  return {"--ca", tls.ca, "--cert", tls.cert, "--key", tls.key};
}

}  // namespace

TEST_CASE("crackvis-render says what is wrong with its data service's address",
          "[server][integration]") {
  auto services = startServices();
  SECTION("nothing listens there") {
    const int port = closedPort();
    auto render = startRenderServer(renderTo(*services.data, fmt::format("127.0.0.1:{}", port)));
    const grpc::Status status = openCrackView(*render);
    CHECK(status.error_code() == grpc::StatusCode::UNAVAILABLE);
    CHECK_THAT(status.error_message(),
               Catch::Contains(fmt::format("no crackvis-data at 127.0.0.1:{} (connection refused): "
                                           "is it running? see docs/deploy.md",
                                           port)));
  }
  SECTION("it is a crackvis-render") {
    auto render = startRenderServer(renderTo(*services.data, services.render->address()));
    const grpc::Status status = openCrackView(*render);
    CHECK(status.error_code() == grpc::StatusCode::FAILED_PRECONDITION);
    CHECK_THAT(status.error_message(),
               Catch::Contains(fmt::format("{} is a crackvis-render, not a crackvis-data",
                                           services.render->address())));
  }
  SECTION("--data-insecure against a crackvis-data with TLS") {
    auto config = renderTo(*services.data, services.data->address());
    config.data.insecure = true;
    auto render = startRenderServer(config);
    const grpc::Status status = openCrackView(*render);
    CHECK(status.error_code() == grpc::StatusCode::UNAVAILABLE);
    CHECK_THAT(status.error_message(),
               Catch::Contains(fmt::format("{} speaks TLS, but --data-insecure asked for plaintext",
                                           services.data->address())) &&
                   Catch::Contains("--data-ca, --data-cert, --data-key"));
  }
  SECTION("a data service address without a port is refused at start") {
    auto config = renderTo(*services.data, "localhost");
    auto refused = service::RenderServer::start(config);
    REQUIRE_FALSE(refused.isOk());
    CHECK_THAT(refused.status().message(),
               Catch::Contains("--data-server (data_service.target) 'localhost': expected "
                               "HOST:PORT with the port"));
  }
  // The working connection, for contrast: the same check passes it.
  CHECK(openCrackView(*services.render).ok());
}

TEST_CASE("crackvis-render connects to its data service as it starts, or once that is up",
          "[server][integration]") {
  auto services = startServices();
  // Before any call: the first user's file open does not make the connection.
  CHECK(waitUntil([&] { return services.render->dataServiceConnected(); }, 10.0));
  // A data service that starts after crackvis-render: sessions fail while it
  // is down and open once it is up (at the next try, about 5 s apart at most).
  const int port = closedPort();
  auto render = startRenderServer(renderTo(*services.data, fmt::format("127.0.0.1:{}", port)));
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  CHECK_FALSE(render->dataServiceConnected());
  CHECK(openCrackView(*render).error_code() == grpc::StatusCode::UNAVAILABLE);
  auto config = baseConfig();
  config.listen = fmt::format("127.0.0.1:{}", port);
  config.dataRoot = crackRoot().path().string();
  auto late = startServer(config);
  CHECK(waitUntil([&] { return openCrackView(*render).ok(); }, 20.0));
  CHECK(render->dataServiceConnected());
}

TEST_CASE("A data client that reached a crackvis-render says so", "[server][integration]") {
  // What `crackvis bench transfer --server` and crackvis-render's sources use.
  auto services = startServices();
  dataservice::ClientOptions options;
  options.target = services.render->address();
  options.tls = clientTls("client");
  options.timeoutSeconds = 20.0;
  auto client = dataservice::DataClient::connect(options);
  REQUIRE(client.isOk());
  auto files = client->listFiles();
  REQUIRE_FALSE(files.isOk());
  CHECK(files.status().message() ==
        fmt::format("{} is a crackvis-render, not a crackvis-data", services.render->address()));
  CHECK(client->serverProgram() == "crackvis-render");
}

TEST_CASE("crackvis bench render and health name the server they reached",
          "[server][integration][cli]") {
  auto services = startServices();
  SECTION("bench render pointed at crackvis-data") {
    std::vector<std::string> argv{
        CRACKVIS_CLI, "bench",     "render", "--server", services.data->address(),
        "--file",     "cuboidA.h5"};
    const auto flags = certificateFlags();
    argv.insert(argv.end(), flags.begin(), flags.end());
    const auto result = runProcess(argv);
    INFO(result.err);
    CHECK(result.exitCode == 1);
    REQUIRE(lines(result.err).size() == 1);
    CHECK(result.err == fmt::format("crackvis bench render: {} is a crackvis-data, not a "
                                    "crackvis-render\n",
                                    services.data->address()));
  }
  SECTION("health of each") {
    for (const auto& [address, program] :
         {std::pair{services.data->address(), "crackvis-data"},
          std::pair{services.render->address(), "crackvis-render"}}) {
      std::vector<std::string> argv{CRACKVIS_CLI, "health", address};
      const auto flags = certificateFlags();
      argv.insert(argv.end(), flags.begin(), flags.end());
      const auto result = runProcess(argv);
      CHECK(result.exitCode == 0);
      CHECK(result.out == fmt::format("{}: SERVING ({})\n", address, program));
    }
  }
  SECTION("health of a service the server does not have") {
    std::vector<std::string> argv{CRACKVIS_CLI, "health", services.render->address(), "--service",
                                  "crackvis.v1.DataService"};
    const auto flags = certificateFlags();
    argv.insert(argv.end(), flags.begin(), flags.end());
    const auto result = runProcess(argv);
    CHECK(result.exitCode == 1);
    CHECK(result.err == fmt::format("crackvis health: {} (a crackvis-render) does not serve "
                                    "'crackvis.v1.DataService'\n",
                                    services.render->address()));
  }
}
