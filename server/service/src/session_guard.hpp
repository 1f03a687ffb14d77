// The exception boundary of a session's thread, shared by the session's
// loop (session.cpp) and its worker's recovery (session_worker.cpp).
// Private to the service library.
#pragma once

#include <string>
#include <string_view>

#include <fmt/format.h>

#include <crackvis/common/exception_boundary.hpp>
#include <crackvis/common/log.hpp>
#include <crackvis/common/status.hpp>

namespace crackvis::service {

// Runs `work` on a session's thread. An exception (a bug, or a library that
// throws on data it should have refused) fails only this piece of work with
// an INTERNAL error and an event line; it never escapes the thread, which
// would end the process for every user.
template <typename Work>
Status guarded(const std::string& session, std::string_view during, Work&& work) noexcept {
  return guardedCall(work, [&](std::string_view detail) {
    log::event(
        stderr, "crackvis-render", "session_exception",
        {{"session", session}, {"during", std::string(during)}, {"detail", std::string(detail)}});
    return failedOnException(fmt::format("session {}: {}", session, during), detail);
  });
}

}  // namespace crackvis::service
