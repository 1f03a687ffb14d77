// crackvis: the command-line tool (generate, info; sim, extract, bench as
// they land). Parses options, runs one subcommand, maps failures to exit codes.
#include <cstdio>
#include <exception>
#include <map>

#include "commands.hpp"

namespace crackvis::cli {
namespace {
std::string g_invocation;
}  // namespace

const std::string& invocation() {
  return g_invocation;
}

void printError(const char* command, const std::string& message) {
  std::fprintf(stderr, "crackvis %s: %s\n", command, message.c_str());
}

}  // namespace crackvis::cli

int main(int argc, char** argv) {
  using namespace crackvis::cli;
  for (int i = 0; i < argc; ++i) {
    crackvis::cli::g_invocation += (i == 0 ? "crackvis" : std::string(" ") + argv[i]);
  }
  CLI::App app{
      "crackvis: crack surfaces in lattice DEM simulations.\n"
      "Data sets are HDF5 files in the crackvis-dem layout (docs/data-format.md).",
      "crackvis"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "crackvis 0.1.0");
  std::map<CLI::App*, Action> actions;
  auto add = [&](Action (*registerCommand)(CLI::App&)) {
    const size_t before = app.get_subcommands({}).size();
    Action action = registerCommand(app);
    actions[app.get_subcommands({}).at(before)] = std::move(action);
  };
  add(addGenerateCommand);
  add(addInfoCommand);

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
    for (auto& [command, action] : actions) {
      if (command->parsed()) {
        return action();
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
