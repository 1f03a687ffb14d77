// One line per call: when, who (user, certificate, peer), what (method,
// file), how much (bytes of data sent, seconds) and how it ended. Lines are
// key=value pairs with strings quoted, so they grep and parse easily:
//
//   2025-05-01T10:00:00.123Z method=Read user="alice" cert="crackvis-client"
//   peer="ipv4:127.0.0.1:53412" file="alice/run.h5" bytes=3538944 seconds=0.004127 status=OK
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <mutex>
#include <string>

#include <crackvis/common/status.hpp>

namespace crackvis::rpc {

struct AccessRecord {
  std::string method;  // ListFiles, Describe, Read, Fetch, RawTls, OpenSession, Stream, ...
  std::string user;
  std::string certificateName;
  std::string peer;
  std::string file;  // as the client named it (the log quotes at most kMaxEchoedChars)
  std::uint64_t bytes = 0;
  double seconds = 0.0;
  std::string status = "OK";  // a gRPC status name
  std::string detail;         // the error message, if any
};

class AccessLog {
 public:
  // "-": stderr; "": no log; anything else: a file opened for appending.
  static Result<std::unique_ptr<AccessLog>> open(const std::string& path);
  AccessLog(const AccessLog&) = delete;
  AccessLog& operator=(const AccessLog&) = delete;
  ~AccessLog();

  void record(const AccessRecord& record);
  static std::string format(const AccessRecord& record);

 private:
  AccessLog(std::FILE* file, bool owned) : m_file(file), m_owned(owned) {}

  std::mutex m_mutex;
  std::FILE* m_file = nullptr;
  bool m_owned = false;
};

}  // namespace crackvis::rpc
