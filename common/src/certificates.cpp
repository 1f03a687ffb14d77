#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include <crackvis/common/certificates.hpp>

namespace crackvis {
namespace {

// The file name of a built-in default ("ca.pem"), or empty for any other path.
std::string defaultName(const std::string& path) {
  const std::string prefix = std::string(kDevelopmentCertificateDir) + "/";
  if (!path.starts_with(prefix) || path.find('/', prefix.size()) != std::string::npos) {
    return {};
  }
  return path.substr(prefix.size());
}

}  // namespace

std::string defaultCertificatePath(std::string_view name) {
  return fmt::format("{}/{}", kDevelopmentCertificateDir, name);
}

std::string locateCertificate(const std::string& path, std::string_view installedDir) {
  const std::string name = defaultName(path);
  std::error_code error;
  if (name.empty() || std::filesystem::exists(path, error)) {
    return path;
  }
  const std::string installed = fmt::format("{}/{}", installedDir, name);
  return std::filesystem::exists(installed, error) ? installed : path;
}

Result<std::string> readCertificateFile(const std::string& path, std::string_view what,
                                        std::string_view setBy, std::string_view installedDir) {
  if (path.empty()) {
    return failedPrecondition(fmt::format("no {} file given: set it with {}", what, setBy));
  }
  const std::string located = locateCertificate(path, installedDir);
  std::ifstream in(located, std::ios::binary);
  if (!in) {
    const std::string reason = std::strerror(errno);
    const std::string name = defaultName(path);
    if (located == path && !name.empty()) {
      return failedPrecondition(fmt::format(
          "cannot read {} '{}': {} (the default, relative to the current folder; not in {} "
          "either): set it with {} (docs/security.md)",
          what, path, reason, installedDir, setBy));
    }
    return failedPrecondition(
        fmt::format("cannot read {} '{}': {} (set by {})", what, located, reason, setBy));
  }
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace crackvis
