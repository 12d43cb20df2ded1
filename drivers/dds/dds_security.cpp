#include "agvslam/drivers/dds/dds_security.h"

#include <openssl/asn1.h>
#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509_vfy.h>

#include <cctype>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <memory>
#include <sstream>

#include "agvslam/core/error.h"
#include "agvslam/drivers/dds/dds_config.h"

#ifndef AGVSLAM_DDS_SECURITY_PLUGIN_DIR
#define AGVSLAM_DDS_SECURITY_PLUGIN_DIR ""
#endif

namespace agvslam::drivers::dds {
namespace {

namespace fs = std::filesystem;

constexpr const char* kMakeKeystore = "deploy/make-keystore.sh creates it";

// The three plugins: file name, DDS Security property prefix, init and finalize symbols.
struct Plugin {
  const char* file;
  const char* prefix;
  const char* init;
  const char* finalize;
};
constexpr Plugin kPlugins[] = {
    {"libdds_security_auth.so", "dds.sec.auth.library.", "init_authentication", "finalize_authentication"},
    {"libdds_security_ac.so", "dds.sec.access.library.", "init_access_control", "finalize_access_control"},
    {"libdds_security_crypto.so", "dds.sec.crypto.library.", "init_crypto", "finalize_crypto"},
};

template <class T, void (*Free)(T*)>
struct Deleter {
  void operator()(T* p) const { Free(p); }
};
void bio_free(BIO* b) { BIO_free(b); }
using BioPtr = std::unique_ptr<BIO, Deleter<BIO, bio_free>>;
using X509Ptr = std::unique_ptr<X509, Deleter<X509, X509_free>>;
using KeyPtr = std::unique_ptr<EVP_PKEY, Deleter<EVP_PKEY, EVP_PKEY_free>>;
using StorePtr = std::unique_ptr<X509_STORE, Deleter<X509_STORE, X509_STORE_free>>;
using StoreCtxPtr = std::unique_ptr<X509_STORE_CTX, Deleter<X509_STORE_CTX, X509_STORE_CTX_free>>;
using Pkcs7Ptr = std::unique_ptr<PKCS7, Deleter<PKCS7, PKCS7_free>>;

// OpenSSL's queued errors as one string (and the queue cleared).
std::string openssl_errors() {
  std::string out;
  while (const unsigned long e = ERR_get_error()) {
    char buf[256];
    ERR_error_string_n(e, buf, sizeof buf);
    out += (out.empty() ? "" : "; ") + std::string(buf);
  }
  return out.empty() ? "no detail from OpenSSL" : out;
}

[[noreturn]] void refuse(const std::string& file, const std::string& expected) {
  ERR_clear_error();
  throw InputError(file, "", expected);
}

std::string read_file(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) refuse(path, "expected " + what + " (" + kMakeKeystore + "); the file is missing or unreadable");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

BioPtr memory_bio(const std::string& data) {
  return BioPtr(BIO_new_mem_buf(data.data(), static_cast<int>(data.size())));
}

X509Ptr load_certificate(const std::string& path, const std::string& what) {
  const std::string pem = read_file(path, what);
  const BioPtr bio = memory_bio(pem);
  X509Ptr cert(PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr));
  if (!cert) refuse(path, "expected " + what + " as a PEM X.509 certificate: " + openssl_errors());
  return cert;
}

std::string name_text(const X509_NAME* name) {
  const BioPtr bio(BIO_new(BIO_s_mem()));
  X509_NAME_print_ex(bio.get(), name, 0, XN_FLAG_RFC2253);
  char* data = nullptr;
  const long n = BIO_get_mem_data(bio.get(), &data);
  return std::string(data, static_cast<std::size_t>(n));
}

std::string time_text(const ASN1_TIME* t) {
  const BioPtr bio(BIO_new(BIO_s_mem()));
  ASN1_TIME_print(bio.get(), t);
  char* data = nullptr;
  const long n = BIO_get_mem_data(bio.get(), &data);
  return std::string(data, static_cast<std::size_t>(n));
}

StorePtr store_of(X509* ca) {
  StorePtr store(X509_STORE_new());
  X509_STORE_add_cert(store.get(), ca);
  return store;
}

// The certificate chains to `ca` and both are valid now.
void check_issued_by(X509* cert, const std::string& cert_path, X509* ca, const std::string& ca_path) {
  const StorePtr store = store_of(ca);
  const StoreCtxPtr ctx(X509_STORE_CTX_new());
  X509_STORE_CTX_init(ctx.get(), store.get(), cert, nullptr);
  if (X509_verify_cert(ctx.get()) == 1) return;
  const int err = X509_STORE_CTX_get_error(ctx.get());
  refuse(cert_path, "expected a certificate issued by the identity CA " + ca_path + " (" +
                        name_text(X509_get_subject_name(ca)) + ") and valid now; got " +
                        X509_verify_cert_error_string(err) + " (subject " + name_text(X509_get_subject_name(cert)) +
                        ", issuer " + name_text(X509_get_issuer_name(cert)) + ", valid " +
                        time_text(X509_get0_notBefore(cert)) + " to " + time_text(X509_get0_notAfter(cert)) + ")");
}

// The S/MIME document at `path` verifies against `ca`; returns the signed content.
std::string verified_content(const std::string& path, const std::string& what, X509* ca, const std::string& ca_path) {
  const std::string smime = read_file(path, what);
  const BioPtr in = memory_bio(smime);
  BIO* detached = nullptr;
  const Pkcs7Ptr p7(SMIME_read_PKCS7(in.get(), &detached));
  const BioPtr content(detached);
  if (!p7) {
    refuse(path, "expected " + what + " as an S/MIME signed document (openssl smime -sign): " + openssl_errors());
  }
  const StorePtr store = store_of(ca);
  const BioPtr out(BIO_new(BIO_s_mem()));
  if (PKCS7_verify(p7.get(), nullptr, store.get(), content.get(), out.get(), PKCS7_TEXT) != 1) {
    refuse(path, "expected " + what + " signed by the permissions CA " + ca_path + " (" +
                     name_text(X509_get_subject_name(ca)) +
                     "); the signature does not verify (the document was changed after signing, or signed by "
                     "another CA): " +
                     openssl_errors());
  }
  char* data = nullptr;
  const long n = BIO_get_mem_data(out.get(), &data);
  return std::string(data, static_cast<std::size_t>(n));
}

// Text between <tag> and </tag> after `from` in `xml`; npos-safe ("" when absent).
std::string element(const std::string& xml, const std::string& tag, std::size_t from, std::size_t to) {
  const std::string open = "<" + tag + ">";
  const std::size_t a = xml.find(open, from);
  if (a == std::string::npos || a >= to) return "";
  const std::size_t b = xml.find("</" + tag + ">", a);
  if (b == std::string::npos || b > to) return "";
  std::string text = xml.substr(a + open.size(), b - a - open.size());
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  const std::size_t last = text.find_last_not_of(" \t\r\n");
  return first == std::string::npos ? "" : text.substr(first, last - first + 1);
}

// A distinguished name compared without blanks around ',' and '=' (permissions are hand-written).
std::string normalised_dn(const std::string& dn) {
  std::string out;
  for (std::size_t i = 0; i < dn.size(); ++i) {
    const char c = dn[i];
    if (c == ' ') {
      const char prev = out.empty() ? ',' : out.back();
      std::size_t j = i;
      while (j < dn.size() && dn[j] == ' ') ++j;
      const char next = j < dn.size() ? dn[j] : ',';
      if (prev == ',' || prev == '=' || next == ',' || next == '=') continue;
    }
    out += c;
  }
  return out;
}

// "YYYY-MM-DDTHH:MM:SS" (the DDS Security permissions' dateTime, taken as UTC) -> seconds since the epoch.
bool parse_utc(const std::string& text, std::time_t& t) {
  std::tm tm{};
  std::istringstream in(text.substr(0, 19));
  in >> std::get_time(&tm, "%Y-%m-%dT%H:%M:%S");
  if (in.fail()) return false;
  t = timegm(&tm);
  return true;
}

// The permissions document has a grant for `subject` that is valid now.
void check_grant(const std::string& xml, const std::string& subject, const std::string& path) {
  const std::string want = normalised_dn(subject);
  std::string subjects;
  for (std::size_t at = xml.find("<grant"); at != std::string::npos; at = xml.find("<grant", at + 1)) {
    const std::size_t end = xml.find("</grant>", at);
    const std::string name = element(xml, "subject_name", at, end);
    subjects += (subjects.empty() ? "" : ", ") + name;
    if (normalised_dn(name) != want) continue;
    const std::string not_before = element(xml, "not_before", at, end);
    const std::string not_after = element(xml, "not_after", at, end);
    std::time_t lo = 0, hi = 0;
    if (!parse_utc(not_before, lo) || !parse_utc(not_after, hi)) {
      refuse(path, "expected the grant for " + subject +
                       " to have <validity> <not_before> and <not_after> as YYYY-MM-DDTHH:MM:SS, got '" + not_before +
                       "' and '" + not_after + "'");
    }
    const std::time_t now = std::time(nullptr);
    if (now < lo || now > hi) {
      refuse(path, "expected the grant for " + subject + " to be valid now; it is valid from " + not_before + " to " +
                       not_after + " (UTC)");
    }
    return;
  }
  refuse(path, "expected a grant whose <subject_name> is the certificate's subject " + subject +
                   "; the grants are for " + (subjects.empty() ? std::string("nobody") : subjects));
}

std::string plugin_dir(const DdsSecurityConfig& config) {
  return config.plugin_dir.empty() ? default_security_plugin_dir() : config.plugin_dir;
}

// ROS enclave names: '/' then a ROS name, e.g. /agvslam/agvslamd.
bool valid_enclave(const std::string& e) { return e.size() > 1 && e.front() == '/' && is_ros_name(e.substr(1)); }

}  // namespace

std::string default_security_plugin_dir() { return AGVSLAM_DDS_SECURITY_PLUGIN_DIR; }

const params::Table<DdsSecurityConfig>& dds_security_params() {
  using params::Text;
  static const params::Table<DdsSecurityConfig> table =
      params::Table<DdsSecurityConfig>(
          "dds_security",
          {
              {"enabled", &DdsSecurityConfig::enabled},
              {"keystore", &DdsSecurityConfig::keystore, Text::any(), "an SROS2 keystore directory"},
              {"enclave", &DdsSecurityConfig::enclave, Text::any(), "an enclave name such as /agvslam/agvslamd"},
              {"plugin_dir", &DdsSecurityConfig::plugin_dir, Text::any(),
               "\"\": the directory of libdds_security_auth.so found when agvslam was built"},
          })
          .check(
              "keystore", [](const DdsSecurityConfig& c) { return !c.enabled || !c.keystore.empty(); },
              "a keystore directory when enabled (deploy/make-keystore.sh makes one)")
          .check(
              "enclave", [](const DdsSecurityConfig& c) { return !c.enabled || valid_enclave(c.enclave); },
              "an enclave name: '/'-separated ROS names such as /agvslam/agvslamd")
          .summary([](const DdsSecurityConfig& c) {
            if (!c.enabled) return std::string("plain DDS: anyone on the network can read and publish");
            return "credentials " + fs::path(c.keystore).append("enclaves").string() + c.enclave + ", plugins " +
                   (plugin_dir(c).empty() ? std::string("not found") : plugin_dir(c));
          });
  return table;
}

void DdsSecurityConfig::validate(const std::string& source) const { dds_security_params().validate(source, *this); }

std::string DdsSecurityConfig::describe() const { return dds_security_params().describe(*this); }

EnclaveFiles enclave_files(const DdsSecurityConfig& config) {
  const std::string dir = fs::absolute(fs::path(config.keystore) / "enclaves").string() + config.enclave + "/";
  return EnclaveFiles{dir + "identity_ca.cert.pem",    dir + "cert.pem",       dir + "key.pem",
                      dir + "permissions_ca.cert.pem", dir + "governance.p7s", dir + "permissions.p7s"};
}

EnclaveFiles check_enclave(const DdsSecurityConfig& config) {
  const std::string dir = plugin_dir(config);
  for (const Plugin& p : kPlugins) {
    const std::string path = (fs::path(dir) / p.file).string();
    if (dir.empty() || !fs::exists(path)) {
      refuse(path, "expected Cyclone DDS's security plugin " + std::string(p.file) +
                       " (Debian: package libddsc0debian, /usr/lib/<arch>/libddsc0debian/); set "
                       "dds_security.plugin_dir to the directory that holds it");
    }
  }
  const fs::path enclave_dir = fs::path(enclave_files(config).certificate).parent_path();
  if (!fs::is_directory(enclave_dir)) {
    refuse(enclave_dir.string(), "expected the directory of enclave " + config.enclave + " in keystore " +
                                     config.keystore + " (deploy/make-keystore.sh " + config.keystore + " " +
                                     config.enclave + ":daemon creates it)");
  }
  const EnclaveFiles f = enclave_files(config);
  const X509Ptr identity_ca = load_certificate(f.identity_ca, "the identity CA certificate");
  const X509Ptr cert = load_certificate(f.certificate, "this enclave's identity certificate");
  check_issued_by(cert.get(), f.certificate, identity_ca.get(), f.identity_ca);

  const std::string key_pem = read_file(f.private_key, "this enclave's private key");
  const BioPtr key_bio = memory_bio(key_pem);
  const KeyPtr key(PEM_read_bio_PrivateKey(key_bio.get(), nullptr, nullptr, nullptr));
  if (!key) refuse(f.private_key, "expected an unencrypted PEM private key: " + openssl_errors());
  if (X509_check_private_key(cert.get(), key.get()) != 1) {
    refuse(f.private_key, "expected the private key of " + f.certificate + "; it belongs to another certificate");
  }

  const X509Ptr permissions_ca = load_certificate(f.permissions_ca, "the permissions CA certificate");
  verified_content(f.governance, "the governance document", permissions_ca.get(), f.permissions_ca);
  const std::string permissions =
      verified_content(f.permissions, "this enclave's permissions document", permissions_ca.get(), f.permissions_ca);
  check_grant(permissions, name_text(X509_get_subject_name(cert.get())), f.permissions);
  return f;
}

SecurityQos::SecurityQos(const DdsSecurityConfig& config, const EnclaveFiles& files) : qos_(dds_create_qos()) {
  const std::string dir = plugin_dir(config);
  for (const Plugin& p : kPlugins) {
    const std::string prefix = p.prefix;
    dds_qset_prop(qos_, (prefix + "path").c_str(), (fs::path(dir) / p.file).c_str());
    dds_qset_prop(qos_, (prefix + "init").c_str(), p.init);
    dds_qset_prop(qos_, (prefix + "finalize").c_str(), p.finalize);
  }
  auto file = [](const std::string& path) { return "file:" + path; };
  dds_qset_prop(qos_, "dds.sec.auth.identity_ca", file(files.identity_ca).c_str());
  dds_qset_prop(qos_, "dds.sec.auth.identity_certificate", file(files.certificate).c_str());
  dds_qset_prop(qos_, "dds.sec.auth.private_key", file(files.private_key).c_str());
  dds_qset_prop(qos_, "dds.sec.access.permissions_ca", file(files.permissions_ca).c_str());
  dds_qset_prop(qos_, "dds.sec.access.governance", file(files.governance).c_str());
  dds_qset_prop(qos_, "dds.sec.access.permissions", file(files.permissions).c_str());
}

SecurityQos::~SecurityQos() { dds_delete_qos(qos_); }

}  // namespace agvslam::drivers::dds
