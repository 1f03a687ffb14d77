#include <memory>

#include <fmt/format.h>
#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/x509.h>

#include <crackvis/common/certificates.hpp>
#include <crackvis/tls/tls_material.hpp>

namespace crackvis::tls {
namespace {

struct BioFree {
  void operator()(BIO* bio) const { BIO_free(bio); }
};
struct X509Free {
  void operator()(X509* cert) const { X509_free(cert); }
};
struct KeyFree {
  void operator()(EVP_PKEY* key) const { EVP_PKEY_free(key); }
};

// How the user sets one of the files ("--ca or tls.ca in the configuration file").
std::string setBy(const TlsFiles& files, const char* option) {
  if (files.keyPrefix.empty()) {
    return fmt::format("{}{}", files.flagPrefix, option);
  }
  return fmt::format("{}{} or {}{} in the configuration file", files.flagPrefix, option,
                     files.keyPrefix, option);
}

std::unique_ptr<BIO, BioFree> memoryBio(const std::string& text) {
  return std::unique_ptr<BIO, BioFree>(BIO_new_mem_buf(text.data(), static_cast<int>(text.size())));
}

Result<std::unique_ptr<X509, X509Free>> parseCertificate(const std::string& pem,
                                                         const std::string& path,
                                                         const char* what) {
  auto bio = memoryBio(pem);
  std::unique_ptr<X509, X509Free> cert(PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr));
  if (!cert) {
    return failedPrecondition(
        fmt::format("{} '{}' is not a PEM certificate ({})", what, path, opensslError()));
  }
  return cert;
}

std::string commonName(X509* cert) {
  X509_NAME* subject = X509_get_subject_name(cert);
  char name[256] = {};
  if (subject == nullptr ||
      X509_NAME_get_text_by_NID(subject, NID_commonName, name, sizeof(name)) < 0) {
    return {};
  }
  return name;
}

}  // namespace

std::string opensslError() {
  const unsigned long code = ERR_get_error();
  ERR_clear_error();
  if (code == 0) {
    return "no detail from OpenSSL";
  }
  char text[256];
  ERR_error_string_n(code, text, sizeof(text));
  return text;
}

TlsFiles defaultTlsFiles(const std::string& name, std::string flagPrefix, std::string keyPrefix) {
  return {defaultCertificatePath("ca.pem"), defaultCertificatePath(name + ".pem"),
          defaultCertificatePath(name + ".key"), std::move(flagPrefix), std::move(keyPrefix)};
}

Result<TlsMaterial> loadTlsMaterial(const TlsFiles& given) {
  // Messages name the files read: a default may have been found installed.
  TlsFiles files = given;
  files.ca = locateCertificate(given.ca);
  files.cert = locateCertificate(given.cert);
  files.key = locateCertificate(given.key);
  TlsMaterial material;
  auto ca = readCertificateFile(given.ca, "CA certificate", setBy(files, "ca"));
  if (!ca) {
    return ca.status();
  }
  auto cert = readCertificateFile(given.cert, "certificate", setBy(files, "cert"));
  if (!cert) {
    return cert.status();
  }
  auto key = readCertificateFile(given.key, "private key", setBy(files, "key"));
  if (!key) {
    return key.status();
  }
  if (auto parsed = parseCertificate(*ca, files.ca, "CA certificate"); !parsed) {
    return parsed.status();
  }
  auto parsedCert = parseCertificate(*cert, files.cert, "certificate");
  if (!parsedCert) {
    return parsedCert.status();
  }
  auto keyBio = memoryBio(*key);
  std::unique_ptr<EVP_PKEY, KeyFree> parsedKey(
      PEM_read_bio_PrivateKey(keyBio.get(), nullptr, nullptr, nullptr));
  if (!parsedKey) {
    return failedPrecondition(
        fmt::format("private key '{}' is not a PEM private key ({})", files.key, opensslError()));
  }
  if (X509_check_private_key(parsedCert->get(), parsedKey.get()) != 1) {
    ERR_clear_error();
    return failedPrecondition(
        fmt::format("private key '{}' does not belong to certificate '{}'", files.key, files.cert));
  }
  material.commonName = commonName(parsedCert->get());
  material.caPem = std::move(*ca);
  material.certPem = std::move(*cert);
  material.keyPem = std::move(*key);
  return material;
}

}  // namespace crackvis::tls
