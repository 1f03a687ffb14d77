// The boundary at which an exception stops: threads that must not end the
// process (a render session's, a step cache's prefetch) run their work
// through guardedCall, which turns an exception into an INTERNAL error.
#pragma once

#include <exception>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include <crackvis/common/status.hpp>

namespace crackvis::scene {

// Runs `call` (returning Status or Result<T>). An exception it throws becomes
// INTERNAL "<what> failed on an internal error: <detail>", after
// `onException(detail)` (a log line) has been told.
template <typename Call, typename OnException>
auto guardedCall(std::string_view what, Call&& call, OnException&& onException) noexcept
    -> decltype(call()) {
  std::string detail;
  try {
    return call();
  } catch (const std::exception& e) {
    detail = e.what();
  } catch (...) {
    detail = "an exception of unknown type";
  }
  try {
    onException(std::string_view(detail));
    return internalError(fmt::format("{} failed on an internal error: {}", what, detail));
  } catch (...) {
    return internalError("internal error");  // out of memory for the message
  }
}

}  // namespace crackvis::scene
