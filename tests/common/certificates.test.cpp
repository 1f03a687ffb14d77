// The TLS files' built-in defaults: certs/generated/ relative to the current
// folder, else the installed copy; a file that cannot be read says where it
// was looked for and which option sets it.
#include <filesystem>
#include <fstream>

#include <catch2/catch.hpp>

#include "support/temp_dir.hpp"
#include <crackvis/common/certificates.hpp>

namespace crackvis {
namespace {

using testing::TempDir;

TEST_CASE("A default certificate missing here is read from the installed folder", "[common]") {
  // The tests run in the build tree, which has no certs/generated/.
  REQUIRE_FALSE(std::filesystem::exists(kDevelopmentCertificateDir));
  TempDir installed;
  std::ofstream(installed.file("ca.pem")) << "installed CA\n";
  const std::string path = defaultCertificatePath("ca.pem");
  CHECK(path == "certs/generated/ca.pem");
  const std::string dir = installed.path().string();
  CHECK(locateCertificate(path, dir) == installed.file("ca.pem"));
  auto read = readCertificateFile(path, "CA certificate", "--ca", dir);
  REQUIRE(read.isOk());
  CHECK(*read == "installed CA\n");

  // A path the user gave is never replaced, nor a default the folder lacks.
  CHECK(locateCertificate("mine/ca.pem", dir) == "mine/ca.pem");
  CHECK(locateCertificate(defaultCertificatePath("client.pem"), dir) ==
        "certs/generated/client.pem");
}

TEST_CASE("A certificate that cannot be read names its option and where it was looked for",
          "[common]") {
  TempDir installed;
  const std::string dir = installed.path().string();
  SECTION("a default, found in neither place") {
    auto read = readCertificateFile(defaultCertificatePath("client.pem"), "certificate",
                                    "--cert or tls.cert in the configuration file", dir);
    REQUIRE_FALSE(read.isOk());
    CHECK(read.status().code() == StatusCode::kFailedPrecondition);
    const std::string& message = read.status().message();
    CHECK_THAT(message, Catch::Contains("cannot read certificate 'certs/generated/client.pem'"));
    CHECK_THAT(message, Catch::Contains("relative to the current folder"));
    CHECK_THAT(message, Catch::Contains("not in " + dir));
    CHECK_THAT(message, Catch::Contains("--cert or tls.cert in the configuration file"));
    CHECK(message.find('\n') == std::string::npos);
  }
  SECTION("a file the user named") {
    auto read = readCertificateFile(installed.file("absent.key"), "private key", "--data-key", dir);
    REQUIRE_FALSE(read.isOk());
    CHECK_THAT(read.status().message(),
               Catch::Contains("cannot read private key '" + installed.file("absent.key") + "'") &&
                   Catch::Contains("No such file") && Catch::Contains("(set by --data-key)"));
  }
  SECTION("no file at all") {
    auto read = readCertificateFile("", "CA certificate", "--ca", dir);
    CHECK(read.status().message() == "no CA certificate file given: set it with --ca");
  }
}

}  // namespace
}  // namespace crackvis
