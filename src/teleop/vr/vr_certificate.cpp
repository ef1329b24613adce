#include "pmg/teleop/vr_certificate.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <openssl/bio.h>
#include <openssl/bn.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/rand.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <system_error>

namespace pmg::teleop {

namespace fs = std::filesystem;

namespace {

constexpr const char* kCertName = "bridge.crt";
constexpr const char* kKeyName = "bridge.key";
constexpr const char* kTokenName = "token";
constexpr long kValiditySeconds = 365L * 24 * 3600;

struct Free {
  void operator()(EVP_PKEY* p) const { EVP_PKEY_free(p); }
  void operator()(X509* p) const { X509_free(p); }
  void operator()(X509_EXTENSION* p) const { X509_EXTENSION_free(p); }
  void operator()(BIGNUM* p) const { BN_free(p); }
  void operator()(BIO* p) const { BIO_free(p); }
  void operator()(GENERAL_NAMES* p) const { GENERAL_NAMES_free(p); }
  void operator()(std::FILE* p) const { std::fclose(p); }
};
template <class T>
using Ptr = std::unique_ptr<T, Free>;

std::string opensslError() {
  std::string s;
  while (const unsigned long e = ERR_get_error()) {
    char buf[256];
    ERR_error_string_n(e, buf, sizeof buf);
    s += s.empty() ? "" : "; ";
    s += buf;
  }
  return s.empty() ? "unknown OpenSSL error" : s;
}

[[noreturn]] void fail(const fs::path& file, const std::string& why) {
  throw std::runtime_error(file.string() + ": " + why);
}

/// Refuses files that a group or others can access, or that another user owns.
void requirePrivateFile(const fs::path& file) {
  struct stat st {};
  if (::stat(file.c_str(), &st) != 0) fail(file, std::string("cannot stat (") + std::strerror(errno) + ")");
  if (!S_ISREG(st.st_mode)) fail(file, "not a regular file");
  if ((st.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%03o", static_cast<unsigned>(st.st_mode & 0777));
    fail(file, std::string("accessible by group or others (mode ") + mode + "); run: chmod 600 " + file.string());
  }
  if (st.st_uid != ::geteuid()) fail(file, "owned by another user");
}

/// Writes @p content to @p file atomically (temporary file with @p mode in the same folder, then
/// rename). Never leaves a partial file under the final name.
void writeFileAtomically(const fs::path& file, const std::string& content, mode_t mode) {
  const fs::path tmp = file.string() + ".tmp" + std::to_string(::getpid());
  ::unlink(tmp.c_str());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
  if (fd < 0) fail(file, std::string("cannot create (") + std::strerror(errno) + ")");
  std::size_t done = 0;
  while (done < content.size()) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = errno;
      ::close(fd);
      ::unlink(tmp.c_str());
      fail(file, std::string("cannot write (") + std::strerror(err) + ")");
    }
    done += static_cast<std::size_t>(n);
  }
  ::fchmod(fd, mode);  // independent of the umask
  ::fsync(fd);
  ::close(fd);
  if (::rename(tmp.c_str(), file.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    fail(file, std::string("cannot rename into place (") + std::strerror(err) + ")");
  }
}

void ensureDir(const fs::path& dir) {
  std::error_code ec;
  if (fs::is_directory(dir, ec)) return;
  fs::create_directories(dir, ec);
  if (ec) fail(dir, "cannot create folder (" + ec.message() + ")");
  ::chmod(dir.c_str(), 0700);
}

std::string bioString(BIO* bio) {
  char* data = nullptr;
  const long n = BIO_get_mem_data(bio, &data);
  return n > 0 ? std::string(data, static_cast<std::size_t>(n)) : std::string();
}

bool isIpLiteral(const std::string& s) {
  unsigned char buf[16];
  return ::inet_pton(AF_INET, s.c_str(), buf) == 1 || ::inet_pton(AF_INET6, s.c_str(), buf) == 1;
}

bool isDnsName(const std::string& s) {
  if (s.empty() || s.size() > 253) return false;
  return std::all_of(s.begin(), s.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '.';
  });
}

void addExtension(X509* x, X509V3_CTX* ctx, int nid, const std::string& value, const fs::path& file) {
  Ptr<X509_EXTENSION> ext(X509V3_EXT_conf_nid(nullptr, ctx, nid, value.c_str()));
  if (!ext || X509_add_ext(x, ext.get(), -1) != 1)
    fail(file, "cannot add extension '" + value + "': " + opensslError());
}

void generate(const fs::path& cert_file, const fs::path& key_file, const std::vector<std::string>& names) {
  Ptr<EVP_PKEY> key(EVP_PKEY_Q_keygen(nullptr, nullptr, "EC", "P-256"));
  if (!key) fail(key_file, "cannot generate a P-256 key: " + opensslError());
  Ptr<X509> x(X509_new());
  if (!x) fail(cert_file, opensslError());
  X509_set_version(x.get(), 2);  // v3
  Ptr<BIGNUM> serial(BN_new());
  if (!serial || BN_rand(serial.get(), 127, BN_RAND_TOP_ANY, BN_RAND_BOTTOM_ANY) != 1 ||
      BN_to_ASN1_INTEGER(serial.get(), X509_get_serialNumber(x.get())) == nullptr)
    fail(cert_file, "cannot make a serial number: " + opensslError());
  X509_gmtime_adj(X509_getm_notBefore(x.get()), -3600);  // an hour back: headset clock skew
  X509_gmtime_adj(X509_getm_notAfter(x.get()), kValiditySeconds);
  X509_set_pubkey(x.get(), key.get());
  X509_NAME* name = X509_get_subject_name(x.get());
  X509_NAME_add_entry_by_txt(name, "O", MBSTRING_ASC, reinterpret_cast<const unsigned char*>("pmg"), -1, -1, 0);
  X509_NAME_add_entry_by_txt(name, "CN", MBSTRING_ASC, reinterpret_cast<const unsigned char*>("pmg_vr_bridge"), -1, -1,
                             0);
  X509_set_issuer_name(x.get(), name);

  std::string san;
  std::vector<std::string> seen;
  for (const std::string& n : names) {
    if (std::find(seen.begin(), seen.end(), n) != seen.end()) continue;
    std::string entry;
    if (isIpLiteral(n))
      entry = "IP:" + n;
    else if (isDnsName(n))
      entry = "DNS:" + n;
    else
      continue;  // a host name with characters a certificate cannot carry
    seen.push_back(n);
    san += (san.empty() ? "" : ",") + entry;
  }
  X509V3_CTX ctx;
  X509V3_set_ctx_nodb(&ctx);
  X509V3_set_ctx(&ctx, x.get(), x.get(), nullptr, nullptr, 0);
  addExtension(x.get(), &ctx, NID_basic_constraints, "critical,CA:FALSE", cert_file);
  addExtension(x.get(), &ctx, NID_key_usage, "critical,digitalSignature", cert_file);
  addExtension(x.get(), &ctx, NID_ext_key_usage, "serverAuth", cert_file);
  addExtension(x.get(), &ctx, NID_subject_key_identifier, "hash", cert_file);
  addExtension(x.get(), &ctx, NID_subject_alt_name, san, cert_file);
  if (X509_sign(x.get(), key.get(), EVP_sha256()) <= 0) fail(cert_file, "cannot sign: " + opensslError());

  Ptr<BIO> key_bio(BIO_new(BIO_s_mem()));
  Ptr<BIO> cert_bio(BIO_new(BIO_s_mem()));
  if (!key_bio || !cert_bio ||
      PEM_write_bio_PrivateKey(key_bio.get(), key.get(), nullptr, nullptr, 0, nullptr, nullptr) != 1 ||
      PEM_write_bio_X509(cert_bio.get(), x.get()) != 1)
    fail(cert_file, "cannot encode PEM: " + opensslError());
  writeFileAtomically(key_file, bioString(key_bio.get()), 0600);
  writeFileAtomically(cert_file, bioString(cert_bio.get()), 0644);
}

Ptr<X509> readCert(const fs::path& file) {
  Ptr<std::FILE> f(std::fopen(file.c_str(), "r"));
  if (!f) fail(file, std::string("cannot open (") + std::strerror(errno) + ")");
  Ptr<X509> x(PEM_read_X509(f.get(), nullptr, nullptr, nullptr));
  if (!x) fail(file, "not a PEM certificate: " + opensslError());
  return x;
}

Ptr<EVP_PKEY> readKey(const fs::path& file) {
  requirePrivateFile(file);
  Ptr<std::FILE> f(std::fopen(file.c_str(), "r"));
  if (!f) fail(file, std::string("cannot open (") + std::strerror(errno) + ")");
  Ptr<EVP_PKEY> k(PEM_read_PrivateKey(f.get(), nullptr, nullptr, nullptr));
  if (!k) fail(file, "not an unencrypted PEM private key: " + opensslError());
  return k;
}

void describe(X509* x, VrCertificateInfo& info) {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  if (X509_digest(x, EVP_sha256(), md, &n) != 1) fail(info.cert_file, "cannot hash: " + opensslError());
  info.sha256_fingerprint.clear();
  for (unsigned int i = 0; i < n; ++i) {
    char b[4];
    std::snprintf(b, sizeof b, i + 1 < n ? "%02X:" : "%02X", md[i]);
    info.sha256_fingerprint += b;
  }
  info.subject_alt_names.clear();
  Ptr<GENERAL_NAMES> gens(static_cast<GENERAL_NAMES*>(X509_get_ext_d2i(x, NID_subject_alt_name, nullptr, nullptr)));
  for (int i = 0; gens && i < sk_GENERAL_NAME_num(gens.get()); ++i) {
    const GENERAL_NAME* g = sk_GENERAL_NAME_value(gens.get(), i);
    if (g->type == GEN_DNS) {
      const ASN1_STRING* s = g->d.dNSName;
      info.subject_alt_names.push_back("DNS:" + std::string(reinterpret_cast<const char*>(ASN1_STRING_get0_data(s)),
                                                            static_cast<std::size_t>(ASN1_STRING_length(s))));
    } else if (g->type == GEN_IPADD) {
      const ASN1_OCTET_STRING* s = g->d.iPAddress;
      char text[INET6_ADDRSTRLEN] = "?";
      const int len = ASN1_STRING_length(s);
      if (len == 4 || len == 16)
        ::inet_ntop(len == 4 ? AF_INET : AF_INET6, ASN1_STRING_get0_data(s), text, sizeof text);
      info.subject_alt_names.push_back(std::string("IP Address:") + text);
    }
  }
  Ptr<BIO> bio(BIO_new(BIO_s_mem()));
  if (bio && ASN1_TIME_print(bio.get(), X509_get0_notAfter(x)) == 1) info.not_after = bioString(bio.get());
}

}  // namespace

fs::path defaultVrConfigDir() {
  if (const char* xdg = std::getenv("XDG_CONFIG_HOME"); xdg != nullptr && *xdg == '/')
    return fs::path(xdg) / "pmg" / "vr";
  if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0')
    return fs::path(home) / ".config" / "pmg" / "vr";
  throw std::runtime_error("neither XDG_CONFIG_HOME nor HOME is set: give --cert-dir");
}

std::vector<std::string> hostNamesAndAddresses() {
  std::vector<std::string> out = {"localhost", "127.0.0.1", "::1"};
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) == 0 && host[0] != '\0') out.emplace_back(host);
  ifaddrs* list = nullptr;
  if (::getifaddrs(&list) == 0) {
    for (const ifaddrs* a = list; a != nullptr; a = a->ifa_next) {
      if (a->ifa_addr == nullptr) continue;
      char text[INET6_ADDRSTRLEN] = {};
      if (a->ifa_addr->sa_family == AF_INET) {
        ::inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(a->ifa_addr)->sin_addr, text, sizeof text);
      } else if (a->ifa_addr->sa_family == AF_INET6) {
        const auto* in6 = reinterpret_cast<const sockaddr_in6*>(a->ifa_addr);
        if (IN6_IS_ADDR_LINKLOCAL(&in6->sin6_addr)) continue;
        ::inet_ntop(AF_INET6, &in6->sin6_addr, text, sizeof text);
      } else {
        continue;
      }
      if (text[0] != '\0' && std::find(out.begin(), out.end(), text) == out.end()) out.emplace_back(text);
    }
    ::freeifaddrs(list);
  }
  return out;
}

VrCertificateInfo ensureVrCertificate(const fs::path& dir, const std::vector<std::string>& extra_names) {
  VrCertificateInfo info;
  info.cert_file = dir / kCertName;
  info.key_file = dir / kKeyName;
  std::error_code ec;
  const bool have_cert = fs::exists(info.cert_file, ec);
  const bool have_key = fs::exists(info.key_file, ec);
  if (have_cert != have_key)
    fail(have_cert ? info.key_file : info.cert_file, "missing while " +
                                                         (have_cert ? info.cert_file : info.key_file).string() +
                                                         " exists; remove both to generate a new pair");
  bool make = !have_cert;
  if (have_cert) {
    Ptr<X509> x = readCert(info.cert_file);
    Ptr<EVP_PKEY> k = readKey(info.key_file);
    if (X509_check_private_key(x.get(), k.get()) != 1)
      fail(info.key_file, "does not match " + info.cert_file.string() + "; remove both to generate a new pair");
    const std::time_t soon = std::time(nullptr) + 24 * 3600;
    if (X509_cmp_time(X509_get0_notAfter(x.get()), const_cast<std::time_t*>(&soon)) < 0) {
      fs::rename(info.cert_file, info.cert_file.string() + ".old", ec);
      fs::rename(info.key_file, info.key_file.string() + ".old", ec);
      make = true;
    } else {
      describe(x.get(), info);
    }
  }
  if (make) {
    ensureDir(dir);
    std::vector<std::string> names = hostNamesAndAddresses();
    names.insert(names.end(), extra_names.begin(), extra_names.end());
    generate(info.cert_file, info.key_file, names);
    Ptr<X509> x = readCert(info.cert_file);
    readKey(info.key_file);
    describe(x.get(), info);
    info.created = true;
  }
  return info;
}

std::string ensureVrAccessToken(const fs::path& dir) {
  const fs::path file = dir / kTokenName;
  std::error_code ec;
  if (fs::exists(file, ec)) {
    requirePrivateFile(file);
    std::ifstream in(file);
    std::string token;
    std::getline(in, token);
    if (token.size() < 8 || token.size() > 64 || !std::all_of(token.begin(), token.end(), [](char c) {
          return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
        }))
      fail(file, "expected one line of 8 to 64 characters [A-Za-z0-9_-]; remove it to generate a new token");
    return token;
  }
  ensureDir(dir);
  static constexpr char kAlphabet[] = "abcdefghijkmnpqrstuvwxyz23456789";  // 32 symbols, no l/o/0/1
  unsigned char bytes[16];
  if (RAND_bytes(bytes, sizeof bytes) != 1) fail(file, "no random bytes: " + opensslError());
  std::string token;
  for (unsigned char b : bytes) token += kAlphabet[b % 32];
  writeFileAtomically(file, token + "\n", 0600);
  return token;
}

}  // namespace pmg::teleop
