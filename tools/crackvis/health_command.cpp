// crackvis health: the standard grpc.health.v1 check of a running
// crackvis-data or crackvis-render, with mutual TLS, for scripts, container
// health checks and operators. Exit 0 when the server reports SERVING.
#include <fmt/format.h>

#include "commands.hpp"
#include <crackvis/dataservice_client/data_client.hpp>

namespace crackvis::cli {
namespace {

struct HealthOptions {
  std::string server;
  std::string service;
  dataservice::ClientOptions client;
  bool quiet = false;
};

int runHealth(HealthOptions options) {
  if (Status status = checkHostPort("server", options.server); !status) {
    printError("health", status.message());
    return kExitUsage;
  }
  options.client.target = options.server;
  options.client.timeoutSeconds = 5.0;
  auto client = dataservice::DataClient::connect(options.client);
  if (!client) {
    printError("health", client.status().message());
    return kExitFailure;
  }
  if (Status status = client->checkHealth(options.service); !status) {
    // Advice names the address already ("no crackvis-data or ... at HOST:PORT").
    const bool named = status.message().find(options.server) != std::string::npos;
    printError("health",
               named ? status.message() : fmt::format("{}: {}", options.server, status.message()));
    return kExitFailure;
  }
  if (!options.quiet) {
    const std::string program = client->serverProgram();
    std::printf("%s: SERVING%s\n", options.server.c_str(),
                program.empty() ? "" : fmt::format(" ({})", program).c_str());
  }
  return kExitOk;
}

}  // namespace

Command addHealthCommand(CLI::App& parent) {
  auto options = std::make_shared<HealthOptions>();
  auto* command = parent.add_subcommand(
      "health",
      "Ask a running crackvis-data or crackvis-render for its grpc.health.v1 status (mutual "
      "TLS); exit status 0 when it is SERVING, 1 otherwise.");
  command->add_option("server", options->server, "HOST:PORT")->required();
  command->add_option("--service", options->service,
                      "service name to check (default: the server as a whole)");
  command->add_option("--ca", options->client.tls.ca, "CA certificate (PEM)")
      ->capture_default_str();
  command->add_option("--cert", options->client.tls.cert, "client certificate (PEM)")
      ->capture_default_str();
  command->add_option("--key", options->client.tls.key, "client private key (PEM)")
      ->capture_default_str();
  command->add_option("--server-name", options->client.serverName,
                      "name the server's certificate must carry (default: HOST)");
  command->add_flag("--insecure", options->client.insecure, "plaintext (a server on --insecure)");
  command->add_flag("-q,--quiet", options->quiet, "print nothing when healthy");
  return {command, [options] { return runHealth(*options); }};
}

}  // namespace crackvis::cli
