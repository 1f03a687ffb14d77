// crackvis-client run as a user starts it: the environment it gets, and the
// lines it printed itself. Shared by the tests with and without services.
#pragma once

#include <string>
#include <vector>

#include "support/process.hpp"

namespace crackvis::testing {

inline const std::string kClient = CRACKVIS_CLIENT;

// The client with this environment ("-u NAME" removes, "NAME=value" sets).
inline ProcessResult runClient(const std::vector<std::string>& environment,
                               const std::vector<std::string>& args) {
  std::vector<std::string> argv{"env"};
  argv.insert(argv.end(), environment.begin(), environment.end());
  argv.push_back(kClient);
  argv.insert(argv.end(), args.begin(), args.end());
  return runProcess(argv);
}

inline const std::vector<std::string> kNoDisplay{"-u", "DISPLAY",        "-u", "WAYLAND_DISPLAY",
                                                 "-u", "QT_QPA_PLATFORM"};
inline const std::vector<std::string> kOffscreen{"QT_QPA_PLATFORM=offscreen"};

// The lines crackvis-client printed itself (Qt's own notes, such as the
// offscreen plugin's, are not its messages).
inline std::vector<std::string> clientLines(const std::string& err) {
  std::vector<std::string> own;
  for (const std::string& line : lines(err)) {
    if (line.starts_with("crackvis-client: ")) {
      own.push_back(line);
    }
  }
  return own;
}

}  // namespace crackvis::testing
