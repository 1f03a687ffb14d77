#include <array>
#include <charconv>
#include <optional>

#include <fmt/format.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/rand.h>
#include <openssl/sha.h>

#include <crackvis/common/base64.hpp>
#include <crackvis/rpc_server/credentials.hpp>

namespace crackvis::rpc {

namespace {

constexpr std::string_view kScheme = "pbkdf2-sha256";
constexpr std::string_view kTokenScheme = "sha256$";
constexpr std::size_t kSaltBytes = 16;
constexpr std::size_t kHashBytes = 32;
constexpr std::size_t kMaxCachedCredentials = 4096;

// Adapters to crackvis/common/base64.hpp for the byte arrays used here.
std::string base64(const unsigned char* data, std::size_t size) {
  return base64Encode({reinterpret_cast<const char*>(data), size});
}

bool unbase64(std::string_view text, std::string& out) {
  auto decoded = base64Decode(text);
  if (!decoded) {
    return false;
  }
  out = std::move(*decoded);
  return true;
}

bool pbkdf2(std::string_view secret, const std::string& salt, int iterations,
            std::array<unsigned char, kHashBytes>& out) {
  return PKCS5_PBKDF2_HMAC(secret.data(), static_cast<int>(secret.size()),
                           reinterpret_cast<const unsigned char*>(salt.data()),
                           static_cast<int>(salt.size()), iterations, EVP_sha256(),
                           static_cast<int>(out.size()), out.data()) == 1;
}

std::array<unsigned char, SHA256_DIGEST_LENGTH> sha256(std::string_view text) {
  std::array<unsigned char, SHA256_DIGEST_LENGTH> digest{};
  SHA256(reinterpret_cast<const unsigned char*>(text.data()), text.size(), digest.data());
  return digest;
}

std::string sha256Hex(std::string_view text) {
  const auto digest = sha256(text);
  std::string hex;
  for (unsigned char byte : digest) {
    hex += fmt::format("{:02x}", byte);
  }
  return hex;
}

bool startsWith(std::string_view text, std::string_view prefix) {
  return text.size() >= prefix.size() && text.substr(0, prefix.size()) == prefix;
}

// "sha256$<base64>": one SHA-256 of the token, compared in constant time.
bool verifyToken(std::string_view token, std::string_view hash) {
  std::string expected;
  if (!unbase64(hash.substr(kTokenScheme.size()), expected) ||
      expected.size() != SHA256_DIGEST_LENGTH) {
    return false;
  }
  const auto actual = sha256(token);
  return CRYPTO_memcmp(actual.data(), expected.data(), actual.size()) == 0;
}

// The peer's address without its port: "ipv4:127.0.0.1:53412" -> "ipv4:127.0.0.1",
// so that a client's new connections count together.
std::string peerAddress(std::string_view peer) {
  const std::size_t colon = peer.rfind(':');
  const std::size_t scheme = peer.find(':');
  return std::string(colon == std::string_view::npos || colon == scheme ? peer
                                                                        : peer.substr(0, colon));
}

}  // namespace

Result<std::string> hashSecret(std::string_view secret, int iterations) {
  if (secret.empty()) {
    return invalidArgument("refusing to hash an empty secret");
  }
  if (iterations < 1000) {
    return invalidArgument("PBKDF2 needs at least 1000 iterations");
  }
  std::array<unsigned char, kSaltBytes> salt{};
  if (RAND_bytes(salt.data(), static_cast<int>(salt.size())) != 1) {
    return internalError("RAND_bytes failed");
  }
  std::array<unsigned char, kHashBytes> hash{};
  const std::string saltText(reinterpret_cast<const char*>(salt.data()), salt.size());
  if (!pbkdf2(secret, saltText, iterations, hash)) {
    return internalError("PKCS5_PBKDF2_HMAC failed");
  }
  return fmt::format("{}${}${}${}", kScheme, iterations, base64(salt.data(), salt.size()),
                     base64(hash.data(), hash.size()));
}

Result<std::string> hashToken(std::string_view token) {
  if (token.empty()) {
    return invalidArgument("refusing to hash an empty token");
  }
  const auto digest = sha256(token);
  return std::string(kTokenScheme) + base64(digest.data(), digest.size());
}

bool verifySecret(std::string_view secret, std::string_view hash) {
  if (startsWith(hash, kTokenScheme)) {
    return verifyToken(secret, hash);
  }
  // scheme$iterations$salt$hash
  std::array<std::string_view, 4> parts;
  std::size_t start = 0;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::size_t end = i + 1 < parts.size() ? hash.find('$', start) : hash.size();
    if (end == std::string_view::npos) {
      return false;
    }
    parts[i] = hash.substr(start, end - start);
    start = end + 1;
  }
  int iterations = 0;
  const auto [ptr, error] =
      std::from_chars(parts[1].data(), parts[1].data() + parts[1].size(), iterations);
  std::string salt;
  std::string expected;
  if (parts[0] != kScheme || error != std::errc() || ptr != parts[1].data() + parts[1].size() ||
      iterations < 1000 || !unbase64(parts[2], salt) || !unbase64(parts[3], expected) ||
      expected.size() != kHashBytes) {
    return false;
  }
  std::array<unsigned char, kHashBytes> actual{};
  return pbkdf2(secret, salt, iterations, actual) &&
         CRYPTO_memcmp(actual.data(), expected.data(), kHashBytes) == 0;
}

Result<std::string> generateToken() {
  std::array<unsigned char, 32> bytes{};
  if (RAND_bytes(bytes.data(), static_cast<int>(bytes.size())) != 1) {
    return internalError("RAND_bytes failed");
  }
  std::string token = base64(bytes.data(), bytes.size());
  for (char& c : token) {
    c = c == '+' ? '-' : (c == '/' ? '_' : c);
  }
  while (!token.empty() && token.back() == '=') {
    token.pop_back();
  }
  return token;
}

bool Caller::mayRead(std::string_view relativePath) const {
  if (!restricted) {
    return true;
  }
  for (const std::string& folder : folders) {
    if (isWithinFolder(relativePath, folder)) {
      return true;
    }
  }
  return false;
}

bool Caller::mayList(std::string_view folder) const {
  if (!restricted) {
    return true;
  }
  for (const std::string& own : folders) {
    if (isWithinFolder(folder, own) || isWithinFolder(own, folder)) {
      return true;
    }
  }
  return false;
}

Status checkNamedPath(const Caller& caller, std::string_view requested) {
  if (!caller.mayRead(requested)) {
    return permissionDenied(
        fmt::format("user '{}' may not read '{}'", caller.name, echoed(requested)));
  }
  return Status::ok();
}

Status checkResolvedPath(const Caller& caller, std::string_view requested,
                         std::string_view resolved) {
  CRACKVIS_RETURN_IF_ERROR(checkNamedPath(caller, requested));
  if (!caller.mayRead(resolved)) {
    return permissionDenied(fmt::format("user '{}' may not read '{}' (it links to '{}')",
                                        caller.name, echoed(requested), echoed(resolved)));
  }
  return Status::ok();
}

Authenticator::Authenticator(std::vector<UserEntry> users) : m_users(std::move(users)) {
  if (!m_users.empty()) {
    // A hash of nothing anyone knows, with the default cost: an unknown
    // name is checked against it, so it takes as long as a known one.
    auto token = generateToken();
    auto dummy = token ? hashSecret(*token) : token.status();
    m_dummyPasswordHash = dummy ? *dummy : std::string();
  }
}

Authenticator::ThrottleKeys Authenticator::throttleKeys(std::string_view authorization,
                                                        std::string_view peer) {
  const std::string address = peerAddress(peer);
  std::string claimed = "a bearer token";
  if (startsWith(authorization, "Basic ")) {
    std::string decoded;
    const bool readable = unbase64(authorization.substr(6), decoded);
    const std::size_t colon = readable ? decoded.find(':') : std::string::npos;
    // The name as claimed, capped: a key is never longer than a name may be.
    claimed = colon == std::string::npos
                  ? std::string("a malformed name")
                  : fmt::format("user '{}'", echoed(decoded.substr(0, colon)));
  } else if (!startsWith(authorization, "Bearer ")) {
    claimed = "another scheme";
  }
  // Only password failures count against the address as a whole: they are
  // what costs a PBKDF2 each; a wrong token costs one SHA-256.
  const bool password = startsWith(authorization, "Basic ");
  return {address + " " + claimed, password ? address : std::string(), claimed, address};
}

Status Authenticator::checkThrottle(const ThrottleKeys& keys) const {
  std::lock_guard lock(m_mutex);
  const auto now = Clock::now();
  auto exceeded = [&](const std::string& key, int limit) -> std::optional<double> {
    auto it = m_failures.find(key);
    if (it == m_failures.end()) {
      return std::nullopt;
    }
    const double age = std::chrono::duration<double>(now - it->second.windowStart).count();
    if (age > kFailureWindowSeconds) {
      m_failures.erase(it);
      return std::nullopt;
    }
    return it->second.count >= limit ? std::optional<double>(age) : std::nullopt;
  };
  auto refuse = [&](const std::string& who, int limit, double age) {
    return resourceExhausted(
        fmt::format("too many failed sign-ins {} ({} in {:.0f} s); retry in {:.0f} s", who, limit,
                    kFailureWindowSeconds, kFailureWindowSeconds - age));
  };
  if (auto age = exceeded(keys.identity, kMaxFailuresPerIdentity)) {
    return refuse(fmt::format("with {} from {}", keys.claimed, keys.peer), kMaxFailuresPerIdentity,
                  *age);
  }
  if (auto age =
          keys.address.empty() ? std::nullopt : exceeded(keys.address, kMaxFailuresPerAddress)) {
    return refuse("from " + keys.peer, kMaxFailuresPerAddress, *age);
  }
  return Status::ok();
}

void Authenticator::recordFailure(const ThrottleKeys& keys) const {
  std::lock_guard lock(m_mutex);
  if (m_failures.size() >= kMaxCachedCredentials) {
    m_failures.clear();  // bounded memory; a flood of addresses only resets the counts
  }
  for (const std::string* key : {&keys.identity, &keys.address}) {
    if (key->empty()) {
      continue;
    }
    Failures& failures = m_failures[*key];
    if (failures.count == 0) {
      failures.windowStart = Clock::now();
    }
    ++failures.count;
  }
}

std::optional<std::size_t> Authenticator::verifiedUser(std::string_view authorization) const {
  std::lock_guard lock(m_mutex);
  if (auto it = m_verified.find(sha256Hex(authorization)); it != m_verified.end()) {
    return it->second;
  }
  return std::nullopt;
}

Result<std::size_t> Authenticator::findUser(std::string_view authorization) const {
  if (auto known = verifiedUser(authorization)) {
    return *known;
  }
  const std::string key = sha256Hex(authorization);
  std::optional<std::size_t> match;
  if (startsWith(authorization, "Bearer ")) {
    const std::string_view token = authorization.substr(7);
    for (std::size_t i = 0; i < m_users.size() && !match; ++i) {
      if (!m_users[i].tokenHash.empty() && verifySecret(token, m_users[i].tokenHash)) {
        match = i;
      }
    }
    if (!match) {
      return unauthenticated("invalid bearer token");
    }
  } else if (startsWith(authorization, "Basic ")) {
    std::string decoded;
    const std::size_t colon = [&] {
      return unbase64(authorization.substr(6), decoded) ? decoded.find(':') : std::string::npos;
    }();
    if (colon == std::string::npos) {
      return unauthenticated("malformed Basic credentials: expected base64 of name:password");
    }
    const std::string_view name(decoded.data(), colon);
    const std::string_view password(decoded.data() + colon + 1, decoded.size() - colon - 1);
    std::optional<std::size_t> named;
    for (std::size_t i = 0; i < m_users.size() && !named; ++i) {
      if (m_users[i].name == name && !m_users[i].passwordHash.empty()) {
        named = i;
      }
    }
    const std::string& hash = named ? m_users[*named].passwordHash : m_dummyPasswordHash;
    if (verifySecret(password, hash) && named) {
      match = named;
    }
    if (!match) {
      return unauthenticated("wrong user name or password");
    }
  } else {
    return unauthenticated(
        "unsupported authorization scheme: send 'Bearer <token>' or 'Basic <base64 "
        "name:password>'");
  }
  std::lock_guard lock(m_mutex);
  if (m_verified.size() >= kMaxCachedCredentials) {
    m_verified.clear();
  }
  m_verified.emplace(key, *match);
  return *match;
}

Result<Caller> Authenticator::authenticate(std::string_view authorization,
                                           std::string_view certificateName,
                                           std::string_view peer) const {
  Caller caller;
  caller.certificateName = certificateName;
  if (m_users.empty()) {
    caller.name = certificateName.empty() ? "anonymous" : std::string(certificateName);
    return caller;
  }
  std::optional<std::size_t> index;
  if (!authorization.empty()) {
    const ThrottleKeys keys = throttleKeys(authorization, peer);
    // Passwords are guessable and slow to check: a throttled name is
    // refused before hashing, unless this very credential was verified
    // before. Tokens are neither, so a valid one always gets through.
    const bool token = startsWith(authorization, "Bearer ");
    if (!token && !verifiedUser(authorization)) {
      CRACKVIS_RETURN_IF_ERROR(checkThrottle(keys));
    }
    auto found = findUser(authorization);
    if (!found) {
      const Status throttled = token ? checkThrottle(keys) : Status::ok();
      recordFailure(keys);
      CRACKVIS_RETURN_IF_ERROR(throttled);
      return found.status();
    }
    index = *found;
  } else {
    for (std::size_t i = 0; i < m_users.size() && !index; ++i) {
      if (!certificateName.empty() && m_users[i].certificateName == certificateName) {
        index = i;
      }
    }
    if (!index) {
      return unauthenticated(
          fmt::format("no credentials: send 'authorization: Bearer <token>' or Basic name:password "
                      "(client certificate '{}' is no user's)",
                      echoed(certificateName)));
    }
  }
  const UserEntry& user = m_users[*index];
  caller.name = user.name;
  caller.restricted = true;
  caller.folders = user.folders;
  return caller;
}

bool isWithinFolder(std::string_view path, std::string_view folder) {
  while (!folder.empty() && folder.back() == '/') {
    folder.remove_suffix(1);
  }
  if (folder.empty() || folder == "*") {
    return true;
  }
  if (path.size() < folder.size() || path.substr(0, folder.size()) != folder) {
    return false;
  }
  return path.size() == folder.size() || path[folder.size()] == '/';
}

}  // namespace crackvis::rpc
