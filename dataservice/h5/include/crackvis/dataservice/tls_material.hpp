// PEM files for mutual TLS, read and checked before any socket opens, so a
// missing or mismatched certificate is one clear message rather than a
// failed handshake later (or an abort inside gRPC).
#pragma once

#include <string>

#include <crackvis/common/status.hpp>

namespace crackvis::dataservice {

struct TlsFiles {
  std::string ca;    // the CA that signs the peer's certificate (PEM)
  std::string cert;  // this side's certificate chain (PEM)
  std::string key;   // its private key (PEM)
};

struct TlsMaterial {
  std::string caPem;
  std::string certPem;
  std::string keyPem;
  std::string commonName;  // CN of `certPem`'s first certificate
};

// Reads the three files; checks that the CA and the certificate parse as
// X.509, the key as a private key, and that the key belongs to the
// certificate. FAILED_PRECONDITION naming the file and the problem.
Result<TlsMaterial> loadTlsMaterial(const TlsFiles& files);

// The oldest error on OpenSSL's queue as text (then clears the queue), for
// messages about a failed handshake or a bad key.
std::string opensslError();

}  // namespace crackvis::dataservice
