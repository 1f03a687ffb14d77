// The crackvis CLI's subcommands. Each add*Command registers one subcommand
// (with its options) under `parent` and returns it with the action to run
// after parsing; an action returns the process exit status (0 success,
// 1 failure on bad input or data with one line on stderr, 2 usage).
#pragma once

#include <functional>
#include <string>

#include <CLI/CLI.hpp>

#include <crackvis/common/status.hpp>

namespace crackvis::cli {

using Action = std::function<int()>;

struct Command {
  CLI::App* app = nullptr;
  Action action;
};

enum ExitCode : int { kExitOk = 0, kExitFailure = 1, kExitUsage = 2 };

// The whole command line of this process, as provenance for files it writes.
const std::string& invocation();

// Prints "crackvis <command>: <message>" as the one line a failure gets.
void printError(const char* command, const std::string& message);

// An address the user gave (`what`: the flag or argument) must be HOST:PORT
// with a port: gRPC would otherwise silently try port 443.
Status checkHostPort(const std::string& what, const std::string& address);

// Top level: crackvis generate | import | info | extract | export | report |
// snapshot | movie | sim | health. addBenchMethodsCommand registers `crackvis bench methods`.
Command addGenerateCommand(CLI::App& parent);
Command addInfoCommand(CLI::App& parent);
Command addExtractCommand(CLI::App& parent);
Command addSnapshotCommand(CLI::App& parent);
Command addMovieCommand(CLI::App& parent);
Command addBenchMethodsCommand(CLI::App& bench);
Command addSimCommand(CLI::App& parent);
Command addHealthCommand(CLI::App& parent);
Command addImportCommand(CLI::App& parent);
Command addExportCommand(CLI::App& parent);
Command addReportCommand(CLI::App& parent);
// Under `crackvis bench`: methods (above) | transfer | render. main.cpp wires
// every command.
Command addBenchTransferCommand(CLI::App& bench);
Command addBenchRenderCommand(CLI::App& bench);
Command addBenchFollowCommand(CLI::App& bench);

}  // namespace crackvis::cli
