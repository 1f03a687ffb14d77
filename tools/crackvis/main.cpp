// crackvis: the command-line tool. Parses options, runs one subcommand, maps
// failures to exit codes. Subcommands live in *_command.cpp files.
#include <cstdio>
#include <exception>
#include <vector>

#include <fmt/format.h>

#include "commands.hpp"

namespace crackvis::cli {
namespace {
std::string& invocationText() {
  static std::string text;
  return text;
}
}  // namespace

const std::string& invocation() {
  return invocationText();
}

void printError(const char* command, const std::string& message) {
  std::fprintf(stderr, "crackvis %s: %s\n", command, message.c_str());
}

Status checkHostPort(const std::string& what, const std::string& address) {
  const std::size_t colon = address.rfind(':');
  const std::string port = colon == std::string::npos ? "" : address.substr(colon + 1);
  const bool digits = !port.empty() && port.size() <= 5 &&
                      port.find_first_not_of("0123456789") == std::string::npos;
  const bool bracketed = address.find('[') == std::string::npos ||
                         (colon > 0 && address[colon - 1] == ']');  // [::1]:50052
  if (colon == std::string::npos || colon == 0 || !digits || !bracketed || std::stoi(port) < 1 ||
      std::stoi(port) > 65535) {
    return invalidArgument(
        fmt::format("{} '{}': expected HOST:PORT with the port (crackvis-data listens on 50051 and "
                    "crackvis-render on 50052 unless configured otherwise)",
                    what, address));
  }
  return Status::ok();
}

}  // namespace crackvis::cli

int main(int argc, char** argv) {
  using namespace crackvis::cli;
  for (int i = 0; i < argc; ++i) {
    invocationText() += i == 0 ? std::string("crackvis") : std::string(" ") + argv[i];
  }
  CLI::App app{
      "crackvis: crack surfaces in lattice DEM simulations.\n"
      "Data sets are HDF5 files in the crackvis-dem layout (docs/data-format.md).",
      "crackvis"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("crackvis ") + CRACKVIS_VERSION);
  auto* bench = app.add_subcommand(
      "bench", "Benchmarks that print ratios against a baseline measured in the same run.");
  bench->require_subcommand(1);

  std::vector<Command> commands;
  commands.push_back(addGenerateCommand(app));
  commands.push_back(addImportCommand(app));
  commands.push_back(addInfoCommand(app));
  commands.push_back(addExtractCommand(app));
  commands.push_back(addExportCommand(app));
  commands.push_back(addSnapshotCommand(app));
  commands.push_back(addMovieCommand(app));
  commands.push_back(addBenchMethodsCommand(*bench));
  commands.push_back(addBenchTransferCommand(*bench));
  commands.push_back(addBenchRenderCommand(*bench));
  commands.push_back(addSimCommand(app));
  commands.push_back(addHealthCommand(app));

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "crackvis: %s\nRun 'crackvis --help' for usage.\n", e.what());
    return kExitUsage;
  }
  try {
    for (const Command& command : commands) {
      if (command.app->parsed()) {
        return command.action();
      }
    }
  } catch (const std::exception& e) {
    // Libraries report expected failures as Status; this is a bug or an
    // allocation failure, still worth one clear line rather than a crash.
    std::fprintf(stderr, "crackvis: internal error: %s\n", e.what());
    return kExitFailure;
  }
  return kExitUsage;
}
