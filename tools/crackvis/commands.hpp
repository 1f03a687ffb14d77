// The crackvis CLI's subcommands. Each registers its options on the app and
// returns the action to run after parsing; an action returns the process exit
// status (0 success, 1 failure on bad input or data, with one line on stderr).
#pragma once

#include <functional>

#include <CLI/CLI.hpp>

namespace crackvis::cli {

using Action = std::function<int()>;

enum ExitCode : int { kExitOk = 0, kExitFailure = 1, kExitUsage = 2 };

// The whole command line of this process, as provenance for files it writes.
const std::string& invocation();

// Prints "crackvis <command>: <message>" as the one line a failure gets.
void printError(const char* command, const std::string& message);

Action addGenerateCommand(CLI::App& app);
Action addInfoCommand(CLI::App& app);

}  // namespace crackvis::cli
