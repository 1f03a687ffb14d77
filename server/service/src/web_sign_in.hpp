// The web front door's sign-ins: a browser has no client certificate, so the
// page signs in once with a user's password or token (POST /api/login, the
// secret in the Authorization header, never in a URL) and gets an opaque
// session cookie (HttpOnly, Secure, SameSite=Strict). This store maps those
// cookies to callers; it holds no secret, only 32 random bytes per sign-in.
// Also the request checks that need no HTTP library: the cookie's value in a
// Cookie header and whether an Origin is the page's own.
#pragma once

#include <chrono>
#include <cstddef>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/rpc_server/credentials.hpp>

namespace crackvis::service {

inline constexpr std::string_view kSignInCookie = "crackvis_session";

class WebSignIns {
 public:
  using Clock = std::chrono::steady_clock;
  struct Limits {
    double idleSeconds = 3600.0;       // unused this long: signed out
    double lifetimeSeconds = 43200.0;  // at most this long, however used (the cookie's Max-Age)
    std::size_t maxSignIns = 10000;    // beyond: the least recently used goes
  };

  WebSignIns() = default;
  explicit WebSignIns(Limits limits) : m_limits(limits) {}

  // A new sign-in of `caller`; returns the cookie's value (base64url).
  Result<std::string> add(rpc::Caller caller, Clock::time_point now = Clock::now());
  // The caller behind a cookie value, if it is signed in; a use renews the
  // idle time.
  std::optional<rpc::Caller> find(std::string_view cookie, Clock::time_point now = Clock::now());
  void remove(std::string_view cookie);
  std::size_t size() const;
  const Limits& limits() const { return m_limits; }

 private:
  struct Entry {
    rpc::Caller caller;
    Clock::time_point created;
    Clock::time_point lastUsed;
  };
  bool expired(const Entry& entry, Clock::time_point now) const;
  void dropOldest();

  Limits m_limits;
  mutable std::mutex m_mutex;
  // Keyed by the SHA-256 of the cookie, so a timing leak of the map's
  // comparisons tells nothing about a live cookie.
  std::map<std::string, Entry> m_entries;
};

// The value of cookie `name` in a Cookie request header ("a=1; b=2").
std::optional<std::string> cookieValue(std::string_view header, std::string_view name);

// Whether a request's Origin is the page's own (`scheme`://`host`, the Host
// header as the browser sent it) or one of `allowed` (configured origins, for
// a page reached through another name). An absent Origin is refused: every
// browser sends one on a POST and a WebSocket upgrade, and a page of another
// site cannot forge it.
bool originAllowed(std::string_view origin, std::string_view scheme, std::string_view host,
                   const std::vector<std::string>& allowed);

// The Set-Cookie value for a sign-in (`value` empty: the sign-out that
// clears it). `secure`: served over TLS.
std::string signInCookieHeader(std::string_view value, double maxAgeSeconds, bool secure);

}  // namespace crackvis::service
