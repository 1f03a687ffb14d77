// The client side of crackvis-data's raw TLS baseline (--raw-tls-listen):
// the bytes of a file over a plain TLS socket with the same certificates,
// for `crackvis bench transfer` to compare gRPC against.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

#include <crackvis/common/status.hpp>
#include <crackvis/tls/tls_material.hpp>

namespace crackvis::dataservice {

struct RawTlsOptions {
  std::string target;         // host:port of the raw TLS baseline
  tls::TlsFiles tls;          // CA, client certificate and key
  std::string serverName;     // default: target's host
  std::string authorization;  // "Bearer <token>" when the server has users
};

struct RawTransfer {
  std::uint64_t bytes = 0;
  double connectSeconds = 0.0;   // TCP connect and TLS handshake
  double transferSeconds = 0.0;  // request sent to last byte received
  std::string protocol;          // "TLSv1.3"
  std::string cipher;            // "TLS_AES_256_GCM_SHA384"
};

// Reads `length` bytes of `file` from `offset` (length 0: to the end),
// handing them to `sink` (may be empty) as they arrive.
Result<RawTransfer> rawTlsRead(const RawTlsOptions& options, const std::string& file,
                               std::uint64_t offset, std::uint64_t length,
                               const std::function<void(const std::byte*, std::size_t)>& sink = {});

}  // namespace crackvis::dataservice
