// Where crackvis finds its TLS files when no flag or configuration names
// them, shared by the services, the CLI and crackvis-client. The built-in
// defaults are the development certificates of a source checkout
// (certs/generated/, made by certs/make-dev-certs.sh, relative to the
// current folder); a default missing there is looked for where
// docs/deploy.md installs the certificates (/etc/crackvis/certs). A file
// that cannot be read is one line naming it, where else a default was
// looked for, and the flag or configuration key that sets it.
#pragma once

#include <string>
#include <string_view>

#include <crackvis/common/status.hpp>

namespace crackvis {

inline constexpr std::string_view kDevelopmentCertificateDir = "certs/generated";
inline constexpr std::string_view kInstalledCertificateDir = "/etc/crackvis/certs";

// "certs/generated/<name>": the built-in default of a TLS file option.
std::string defaultCertificatePath(std::string_view name);

// The file to read for `path`: `path` itself, unless it is a built-in
// default that does not exist here and `installedDir`/<name> does.
std::string locateCertificate(const std::string& path,
                              std::string_view installedDir = kInstalledCertificateDir);

// The contents of the TLS file `path` (located as above); `what` names it
// ("CA certificate") and `setBy` says how the user sets it ("--ca or tls.ca
// in the configuration file"). FAILED_PRECONDITION when it cannot be read.
Result<std::string> readCertificateFile(const std::string& path, std::string_view what,
                                        std::string_view setBy,
                                        std::string_view installedDir = kInstalledCertificateDir);

}  // namespace crackvis
