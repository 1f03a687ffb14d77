// crackvis: the command-line tool. Parses options, runs one subcommand, maps
// failures to exit codes. Subcommands live in *_command.cpp files.
#include <cstdio>
#include <exception>
#include <vector>

#include <fmt/format.h>

#include "commands.hpp"
#include <crackvis/common/spelling.hpp>
#include <crackvis/rpc/connection_advice.hpp>

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
  return rpc::checkHostPort(what, address);  // the client's --connect has the same rule
}

namespace {

// A misspelt subcommand or option, said with the nearest right one
// ("unknown subcommand 'extrat' (did you mean extract?)"); empty when the
// parse failed for another reason (CLI11's message says it then).
std::string misspelling(const CLI::App& app) {
  const CLI::App* deepest = &app;
  std::string path = "crackvis";
  for (auto parsed = deepest->get_subcommands(); !parsed.empty();
       parsed = deepest->get_subcommands()) {
    deepest = parsed.front();
    path += " " + deepest->get_name();
  }
  const std::vector<std::string> extras = deepest->remaining();
  std::vector<std::string> subcommands;
  for (const CLI::App* sub : deepest->get_subcommands([](const CLI::App*) { return true; })) {
    subcommands.push_back(sub->get_name());
  }
  // Where a subcommand was due, the first word is one gone wrong (what
  // follows it belongs to the subcommand meant).
  if (!subcommands.empty() && !extras.empty() && !extras.front().starts_with("-")) {
    const std::string nearest = closestName(extras.front(), subcommands);
    return fmt::format("{}: unknown subcommand '{}' ({})", path, extras.front(),
                       nearest.empty() ? fmt::format("one of: {}", fmt::join(subcommands, ", "))
                                       : fmt::format("did you mean {}?", nearest));
  }
  for (const std::string& arg : extras) {
    if (arg.size() < 2 || arg[0] != '-') {
      continue;
    }
    const std::string given = arg.substr(0, arg.find('='));
    std::vector<std::string> names;
    for (const CLI::Option* option : deepest->get_options()) {
      for (const std::string& name : option->get_lnames()) {
        names.push_back("--" + name);
      }
      for (const std::string& name : option->get_snames()) {
        names.push_back("-" + name);
      }
    }
    const std::string nearest = closestName(given, names);
    return fmt::format(
        "{}: unknown option '{}'{}", path, given,
        nearest.empty() ? std::string() : fmt::format(" (did you mean {}?)", nearest));
  }
  return {};
}

}  // namespace

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
  crackvis::rpc::quietGrpcLogs();  // failures are the one line each command prints
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
  commands.push_back(addReportCommand(app));
  commands.push_back(addSnapshotCommand(app));
  commands.push_back(addMovieCommand(app));
  commands.push_back(addBenchMethodsCommand(*bench));
  commands.push_back(addBenchTransferCommand(*bench));
  commands.push_back(addBenchRenderCommand(*bench));
  commands.push_back(addBenchFollowCommand(*bench));
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
    if (const std::string typo = misspelling(app); !typo.empty()) {
      std::fprintf(stderr, "%s\n", typo.c_str());
    } else {
      std::fprintf(stderr, "crackvis: %s\nRun 'crackvis --help' for usage.\n", e.what());
    }
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
