#include "web_sign_in.hpp"

#include <algorithm>
#include <array>

#include <fmt/format.h>
#include <openssl/sha.h>

#include <crackvis/common/base64.hpp>

namespace crackvis::service {

namespace {

std::string digest(std::string_view cookie) {
  std::array<unsigned char, SHA256_DIGEST_LENGTH> hash{};
  SHA256(reinterpret_cast<const unsigned char*>(cookie.data()), cookie.size(), hash.data());
  return {reinterpret_cast<const char*>(hash.data()), hash.size()};
}

std::string_view trim(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) {
    text.remove_prefix(1);
  }
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) {
    text.remove_suffix(1);
  }
  return text;
}

double secondsBetween(WebSignIns::Clock::time_point from, WebSignIns::Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

}  // namespace

Result<std::string> WebSignIns::add(rpc::Caller caller, Clock::time_point now) {
  auto cookie = rpc::generateToken();  // 32 random bytes, base64url
  if (!cookie) {
    return cookie.status();
  }
  std::lock_guard lock(m_mutex);
  while (m_entries.size() >= m_limits.maxSignIns) {
    dropOldest();
  }
  m_entries[digest(*cookie)] = Entry{std::move(caller), now, now};
  return cookie;
}

std::optional<rpc::Caller> WebSignIns::find(std::string_view cookie, Clock::time_point now) {
  std::lock_guard lock(m_mutex);
  const auto found = m_entries.find(digest(cookie));
  if (found == m_entries.end()) {
    return std::nullopt;
  }
  if (expired(found->second, now)) {
    m_entries.erase(found);
    return std::nullopt;
  }
  found->second.lastUsed = now;
  return found->second.caller;
}

void WebSignIns::remove(std::string_view cookie) {
  std::lock_guard lock(m_mutex);
  m_entries.erase(digest(cookie));
}

std::size_t WebSignIns::size() const {
  std::lock_guard lock(m_mutex);
  return m_entries.size();
}

bool WebSignIns::expired(const Entry& entry, Clock::time_point now) const {
  return secondsBetween(entry.lastUsed, now) > m_limits.idleSeconds ||
         secondsBetween(entry.created, now) > m_limits.lifetimeSeconds;
}

void WebSignIns::dropOldest() {
  const auto oldest = std::min_element(
      m_entries.begin(), m_entries.end(),
      [](const auto& a, const auto& b) { return a.second.lastUsed < b.second.lastUsed; });
  if (oldest != m_entries.end()) {
    m_entries.erase(oldest);
  }
}

std::optional<std::string> cookieValue(std::string_view header, std::string_view name) {
  while (!header.empty()) {
    const std::size_t end = std::min(header.find(';'), header.size());
    const std::string_view pair = trim(header.substr(0, end));
    header.remove_prefix(std::min(end + 1, header.size()));
    const std::size_t equals = pair.find('=');
    if (equals != std::string_view::npos && trim(pair.substr(0, equals)) == name) {
      return std::string(trim(pair.substr(equals + 1)));
    }
  }
  return std::nullopt;
}

bool originAllowed(std::string_view origin, std::string_view scheme, std::string_view host,
                   const std::vector<std::string>& allowed) {
  if (origin.empty() || host.empty()) {
    return false;
  }
  if (origin == fmt::format("{}://{}", scheme, host)) {
    return true;
  }
  return std::find(allowed.begin(), allowed.end(), origin) != allowed.end();
}

std::string signInCookieHeader(std::string_view value, double maxAgeSeconds, bool secure) {
  return fmt::format("{}={}; Path=/; Max-Age={}; HttpOnly; SameSite=Strict{}", kSignInCookie, value,
                     value.empty() ? 0 : static_cast<long long>(maxAgeSeconds),
                     secure ? "; Secure" : "");
}

}  // namespace crackvis::service
