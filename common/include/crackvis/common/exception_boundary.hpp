// The one boundary at which an exception stops, for every place that must not
// let one end the process: the RPC handlers of both services (rpc::guarded,
// which adds the handler's event line), a render session's thread and a step
// cache's prefetch. Expected failures are Status / Result<T>; an exception
// here is a bug, or a library throwing on data it should have refused, and it
// fails only the piece of work it interrupted, with INTERNAL.
#pragma once

#include <exception>
#include <string>
#include <string_view>

#include <crackvis/common/status.hpp>

namespace crackvis {

// The detail of an exception whose type does not derive from std::exception.
inline constexpr std::string_view kUnknownException = "an exception of unknown type";

// Runs `work` (returning Status or Result<T>). An exception it throws becomes
// INTERNAL with the message `onException(detail)` returns (a std::string),
// `detail` being the exception's what(). onException is where the caller logs
// it and decides how much of it the one who asked for the work may see.
// Should onException throw in turn (no memory left for the message), the
// status is INTERNAL "internal error".
template <typename Work, typename OnException>
auto guardedCall(Work&& work, OnException&& onException) noexcept -> decltype(work()) {
  try {
    try {
      return work();
    } catch (const std::exception& error) {
      return internalError(onException(std::string_view(error.what())));
    } catch (...) {
      return internalError(onException(kUnknownException));
    }
  } catch (...) {
    return internalError("internal error");
  }
}

// "<what> failed on an internal error: <detail>": the message for work whose
// exception detail may reach whoever asked for the work.
inline std::string failedOnException(std::string_view what, std::string_view detail) {
  std::string message(what);
  message += " failed on an internal error: ";
  message += detail;
  return message;
}

}  // namespace crackvis
