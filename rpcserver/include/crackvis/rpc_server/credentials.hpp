// The per-user layer on top of mutual TLS, shared by crackvis-data and
// crackvis-render: hashed secrets and the authenticator that turns a call's
// credentials into a Caller with the folders it may read. No gRPC types: a
// service hands it the call's `authorization` metadata, the client
// certificate's common name and the peer.
//
// Bearer tokens are random (32 bytes), so a fast hash is as strong as a slow
// one for them: hashToken() stores "sha256$<hash base64>", checked with one
// SHA-256 per call. Passwords are chosen by people and stay slow:
// "pbkdf2-sha256$<iterations>$<salt base64>$<hash base64>" (PBKDF2-HMAC-
// SHA256, 16-byte random salt, 32-byte hash). Token hashes in the PBKDF2 form
// (made before the fast form existed) are still accepted.
//
// Failed sign-ins are counted per claimed identity and peer address together
// (the user name of Basic credentials, "a bearer token" for tokens), because
// behind a NAT, a proxy or the browser gateway every user shares one
// address. Past kMaxFailuresPerIdentity in kFailureWindowSeconds, passwords
// for that name from that address are refused without hashing; past
// kMaxFailuresPerAddress, any unverified password from that address is. A
// valid credential is never locked out by others' failures: a credential
// verified before passes without a check of the throttle, and a bearer token
// (32 random bytes, one SHA-256 to check, nothing to guess) is always
// checked, a throttled peer's wrong ones refused as RESOURCE_EXHAUSTED.
#pragma once

#include <chrono>
#include <cstddef>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include <crackvis/common/status.hpp>

namespace crackvis::rpc {

// A user of the per-user layer on top of mutual TLS. A caller is this user
// when it sends the token, the name and password, or (with neither) a client
// certificate whose common name is `certificateName`.
struct UserEntry {
  std::string name;
  std::string tokenHash;             // hashSecret() of the bearer token; empty: none
  std::string passwordHash;          // hashSecret() of the password; empty: none
  std::string certificateName;       // client certificate CN that identifies the user; empty: none
  std::vector<std::string> folders;  // sub-folders of the root the user may read; "*": all
};

// Whether `path` (normalized, relative) is `folder` or lies below it; the
// empty folder and "*" contain everything.
bool isWithinFolder(std::string_view path, std::string_view folder);

inline constexpr int kDefaultHashIterations = 200000;
inline constexpr int kMaxFailuresPerIdentity = 10;  // one name (or tokens) from one address
inline constexpr int kMaxFailuresPerAddress = 100;  // every name from one address
inline constexpr double kFailureWindowSeconds = 60.0;

// Hashes a password with a fresh random salt (PBKDF2).
Result<std::string> hashSecret(std::string_view secret, int iterations = kDefaultHashIterations);
// Hashes a random bearer token (SHA-256; see the header comment).
Result<std::string> hashToken(std::string_view token);
// Whether `secret` matches a hash made by hashSecret or hashToken
// (constant-time compare). A malformed hash never matches.
bool verifySecret(std::string_view secret, std::string_view hash);
// A random token for a new user: 32 random bytes, base64url.
Result<std::string> generateToken();

// Who is calling and what they may read.
struct Caller {
  std::string name;             // user name; the certificate CN when users are off
  std::string certificateName;  // CN of the client certificate, if any
  bool restricted = false;      // false: the whole data root
  std::vector<std::string> folders;

  // Whether a normalized path relative to the root lies in the caller's folders.
  bool mayRead(std::string_view relativePath) const;
  // Whether a folder may be listed: it lies in the caller's folders or
  // contains one of them (listing the root shows a user their folders).
  bool mayList(std::string_view folder) const;
};

// The one folder rule for a file, applied by both services: the path as
// named (`requested`, normalized) and the real path it resolves to
// (`resolved`, after symlinks) must both lie in the caller's folders. The
// named path is checked first, before anything about the file is looked up,
// so the answer for another user's file never tells whether it exists.
Status checkNamedPath(const Caller& caller, std::string_view requested);
Status checkResolvedPath(const Caller& caller, std::string_view requested,
                         std::string_view resolved);

class Authenticator {
 public:
  explicit Authenticator(std::vector<UserEntry> users);

  bool usersEnabled() const { return !m_users.empty(); }

  // `authorization` is the call's metadata value ("Bearer <token>" or
  // "Basic <base64 name:password>"), empty when absent; `peer` the caller's
  // address as gRPC names it ("ipv4:127.0.0.1:53412"). UNAUTHENTICATED when
  // users are configured and the credentials match none of them;
  // RESOURCE_EXHAUSTED while the name (or tokens) claimed from the peer's
  // address, or the address as a whole, has too many failures.
  Result<Caller> authenticate(std::string_view authorization, std::string_view certificateName,
                              std::string_view peer = {}) const;

 private:
  using Clock = std::chrono::steady_clock;
  struct Failures {
    int count = 0;
    Clock::time_point windowStart;
  };

  // A failed sign-in is counted under both keys; either past its limit
  // throttles.
  struct ThrottleKeys {
    std::string identity;  // "<address> user '<name>'" or "<address> a bearer token"
    std::string address;   // empty for tokens: only passwords count per address
    std::string claimed;   // for messages: "user 'bob'"
    std::string peer;      // for messages: the address
  };
  static ThrottleKeys throttleKeys(std::string_view authorization, std::string_view peer);
  std::optional<std::size_t> verifiedUser(std::string_view authorization) const;
  Result<std::size_t> findUser(std::string_view authorization) const;
  Status checkThrottle(const ThrottleKeys& keys) const;
  void recordFailure(const ThrottleKeys& keys) const;

  std::vector<UserEntry> m_users;
  std::string m_dummyPasswordHash;  // verified for unknown names: they cost as much as known
  // Verified Basic credentials (SHA-256 of the header -> user), so that
  // PBKDF2 runs once per client rather than once per call.
  mutable std::mutex m_mutex;
  mutable std::unordered_map<std::string, std::size_t> m_verified;
  mutable std::map<std::string, Failures> m_failures;  // by ThrottleKeys' two keys
};

}  // namespace crackvis::rpc
