// Status and Result<T>: how crackvis libraries report expected failures.
//
// Codes mirror the gRPC canonical codes that the services map them to, so a
// failure deep in a reader reaches a remote client with the same meaning.
// Messages name what failed and on which input ("dataset /bonds/pairs in
// a.h5: expected int32, found float64"); they are one line, for people.
#pragma once

#include <cassert>
#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <variant>

namespace crackvis {

enum class StatusCode {
  kOk,
  kInvalidArgument,
  kNotFound,
  kOutOfRange,
  kFailedPrecondition,
  kPermissionDenied,
  kUnauthenticated,
  kResourceExhausted,
  kUnavailable,
  kInternal,
  kCancelled,         // the caller gave up (it cancelled, or went away)
  kDeadlineExceeded,  // the call ran out of time
};

std::string_view toString(StatusCode code);

class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : m_code(code), m_message(std::move(message)) {}

  static Status ok() { return {}; }
  bool isOk() const { return m_code == StatusCode::kOk; }
  explicit operator bool() const { return isOk(); }
  StatusCode code() const { return m_code; }
  const std::string& message() const { return m_message; }

 private:
  StatusCode m_code = StatusCode::kOk;
  std::string m_message;
};

inline Status invalidArgument(std::string message) {
  return {StatusCode::kInvalidArgument, std::move(message)};
}
inline Status notFound(std::string message) {
  return {StatusCode::kNotFound, std::move(message)};
}
inline Status outOfRange(std::string message) {
  return {StatusCode::kOutOfRange, std::move(message)};
}
inline Status failedPrecondition(std::string message) {
  return {StatusCode::kFailedPrecondition, std::move(message)};
}
inline Status internalError(std::string message) {
  return {StatusCode::kInternal, std::move(message)};
}
inline Status permissionDenied(std::string message) {
  return {StatusCode::kPermissionDenied, std::move(message)};
}
inline Status unauthenticated(std::string message) {
  return {StatusCode::kUnauthenticated, std::move(message)};
}
inline Status resourceExhausted(std::string message) {
  return {StatusCode::kResourceExhausted, std::move(message)};
}
inline Status unavailable(std::string message) {
  return {StatusCode::kUnavailable, std::move(message)};
}
inline Status cancelled(std::string message) {
  return {StatusCode::kCancelled, std::move(message)};
}
inline Status deadlineExceeded(std::string message) {
  return {StatusCode::kDeadlineExceeded, std::move(message)};
}

// A client-supplied name as error messages quote it: at most kMaxEchoedChars
// characters, then "...", so a 100 KB name does not come back in a status or
// fill a log line.
inline constexpr std::size_t kMaxEchoedChars = 200;
inline std::string echoed(std::string_view name) {
  if (name.size() <= kMaxEchoedChars) {
    return std::string(name);
  }
  return std::string(name.substr(0, kMaxEchoedChars)) + "...";
}

// A value or the Status that explains why there is none.
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : m_state(std::move(value)) {}        // NOLINT: implicit by design
  Result(Status status) : m_state(std::move(status)) {  // NOLINT: implicit by design
    assert(!std::get<Status>(m_state).isOk() && "a Result holds a value or an error");
  }

  bool isOk() const { return std::holds_alternative<T>(m_state); }
  explicit operator bool() const { return isOk(); }

  const Status& status() const {
    static const Status kOkStatus;
    return isOk() ? kOkStatus : std::get<Status>(m_state);
  }
  T& value() & { return std::get<T>(m_state); }
  const T& value() const& { return std::get<T>(m_state); }
  T&& value() && { return std::get<T>(std::move(m_state)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }

 private:
  std::variant<T, Status> m_state;
};

inline std::string_view toString(StatusCode code) {
  switch (code) {
    case StatusCode::kOk:
      return "OK";
    case StatusCode::kInvalidArgument:
      return "INVALID_ARGUMENT";
    case StatusCode::kNotFound:
      return "NOT_FOUND";
    case StatusCode::kOutOfRange:
      return "OUT_OF_RANGE";
    case StatusCode::kFailedPrecondition:
      return "FAILED_PRECONDITION";
    case StatusCode::kPermissionDenied:
      return "PERMISSION_DENIED";
    case StatusCode::kUnauthenticated:
      return "UNAUTHENTICATED";
    case StatusCode::kResourceExhausted:
      return "RESOURCE_EXHAUSTED";
    case StatusCode::kUnavailable:
      return "UNAVAILABLE";
    case StatusCode::kInternal:
      return "INTERNAL";
    case StatusCode::kCancelled:
      return "CANCELLED";
    case StatusCode::kDeadlineExceeded:
      return "DEADLINE_EXCEEDED";
  }
  return "UNKNOWN";
}

}  // namespace crackvis

// Returns early from the enclosing function with the error of `expr`.
#define CRACKVIS_RETURN_IF_ERROR(expr)           \
  do {                                           \
    ::crackvis::Status crackvisStatus_ = (expr); \
    if (!crackvisStatus_.isOk()) {               \
      return crackvisStatus_;                    \
    }                                            \
  } while (false)
