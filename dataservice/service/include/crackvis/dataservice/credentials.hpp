// The per-user layer on top of mutual TLS: hashed secrets and the
// authenticator that turns a call's credentials into a Caller with the
// folders it may read. No gRPC types: the service hands it the call's
// `authorization` metadata and the client certificate's common name.
//
// Secrets (bearer tokens and passwords) are stored as
// "pbkdf2-sha256$<iterations>$<salt base64>$<hash base64>" (PBKDF2-HMAC-
// SHA256, 16-byte random salt, 32-byte hash), never in clear.
#pragma once

#include <cstddef>
#include <mutex>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dataservice/server_config.hpp>

namespace crackvis::dataservice {

inline constexpr int kDefaultHashIterations = 200000;

// Hashes a secret with a fresh random salt.
Result<std::string> hashSecret(std::string_view secret, int iterations = kDefaultHashIterations);
// Whether `secret` matches a hash made by hashSecret (constant-time compare).
// A malformed hash never matches.
bool verifySecret(std::string_view secret, std::string_view hash);
// A random token for a new user: 32 random bytes, base64url.
Result<std::string> generateToken();

// Who is calling and what they may read.
struct Caller {
  std::string name;             // user name; the certificate CN when users are off
  std::string certificateName;  // CN of the client certificate, if any
  bool restricted = false;      // false: the whole data root
  std::vector<std::string> folders;

  bool mayRead(std::string_view relativePath) const;
};

class Authenticator {
 public:
  explicit Authenticator(std::vector<UserEntry> users) : m_users(std::move(users)) {}

  bool usersEnabled() const { return !m_users.empty(); }

  // `authorization` is the call's metadata value ("Bearer <token>" or
  // "Basic <base64 name:password>"), empty when absent. UNAUTHENTICATED
  // when users are configured and the credentials match none of them.
  Result<Caller> authenticate(std::string_view authorization,
                              std::string_view certificateName) const;

 private:
  Result<std::size_t> findUser(std::string_view authorization) const;

  std::vector<UserEntry> m_users;
  // Verified credentials (SHA-256 of the header -> user), so that PBKDF2
  // runs once per client rather than once per call.
  mutable std::mutex m_cacheMutex;
  mutable std::unordered_map<std::string, std::size_t> m_verified;
};

}  // namespace crackvis::dataservice
