// PEM files for mutual TLS, read and checked before any socket opens, so a
// missing or mismatched certificate is one clear message rather than a
// failed handshake later (or an abort inside gRPC).
#pragma once

#include <string>

#include <crackvis/common/status.hpp>

namespace crackvis::tls {

struct TlsFiles {
  std::string ca;    // the CA that signs the peer's certificate (PEM)
  std::string cert;  // this side's certificate chain (PEM)
  std::string key;   // its private key (PEM)
  // How the user sets them, for messages: flags "--ca", "--cert", "--key"
  // behind this prefix ("--data-" gives --data-ca), and configuration keys
  // behind `keyPrefix` ("tls." gives tls.ca; empty: no configuration file).
  std::string flagPrefix = "--";
  std::string keyPrefix = {};
};

// The built-in defaults: `cert` and `key` are certs/generated/<name>.pem and
// .key beside certs/generated/ca.pem (crackvis/common/certificates.hpp: also
// looked for in /etc/crackvis/certs).
TlsFiles defaultTlsFiles(const std::string& name, std::string flagPrefix = "--",
                         std::string keyPrefix = {});

struct TlsMaterial {
  std::string caPem;
  std::string certPem;
  std::string keyPem;
  std::string commonName;  // CN of `certPem`'s first certificate
};

// Reads the three files (a built-in default missing from the current folder
// from /etc/crackvis/certs); checks that the CA and the certificate parse as
// X.509, the key as a private key, and that the key belongs to the
// certificate. FAILED_PRECONDITION naming the file, the problem and the flag
// or configuration key that sets it.
Result<TlsMaterial> loadTlsMaterial(const TlsFiles& files);

// The oldest error on OpenSSL's queue as text (then clears the queue), for
// messages about a failed handshake or a bad key.
std::string opensslError();

}  // namespace crackvis::tls
