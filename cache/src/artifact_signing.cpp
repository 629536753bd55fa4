// Ed25519 keys, key files and signatures (artifact_signing.hpp), on OpenSSL 3's EVP API.
#include "robodiff/cache/artifact_signing.hpp"

#include <fcntl.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace robodiff::cache {

namespace fs = std::filesystem;

struct detail::KeyHandle {
  explicit KeyHandle(EVP_PKEY* k) : pkey(k) {}
  ~KeyHandle() { EVP_PKEY_free(pkey); }
  KeyHandle(const KeyHandle&) = delete;
  KeyHandle& operator=(const KeyHandle&) = delete;
  EVP_PKEY* pkey;
};

namespace {

using Bio = std::unique_ptr<BIO, decltype(&BIO_free)>;
using MdCtx = std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)>;

// OpenSSL's last error as text (and the queue cleared), for messages.
std::string opensslError() {
  const unsigned long code = ERR_get_error();
  ERR_clear_error();
  if (code == 0) return "no detail from OpenSSL";
  char buf[256];
  ERR_error_string_n(code, buf, sizeof buf);
  return buf;
}

std::string readText(const fs::path& file, const char* what) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw SigningError("cannot read " + std::string(what) + " " + file.string() + ": " + std::strerror(errno));
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Never asks for a passphrase: an encrypted key fails to load (reported by the caller).
int noPassphrase(char*, int, int, void*) { return -1; }

std::shared_ptr<detail::KeyHandle> requireEd25519(EVP_PKEY* pkey, const std::string& origin, const char* what) {
  if (pkey == nullptr)
    throw SigningError(origin + " is not a PEM " + what + " (or it is encrypted, which is not supported): " +
                       opensslError());
  auto handle = std::make_shared<detail::KeyHandle>(pkey);
  if (EVP_PKEY_get_id(pkey) != EVP_PKEY_ED25519)
    throw SigningError(origin + " holds a " + std::string(EVP_PKEY_get0_type_name(pkey) ? EVP_PKEY_get0_type_name(pkey) : "?") +
                       " key; robodiff signs with Ed25519 keys (robodiff keygen makes them)");
  return handle;
}

// First 16 hex digits of the SHA-256 of the raw 32-byte public key.
std::string keyIdOf(EVP_PKEY* pkey) {
  unsigned char raw[64];
  std::size_t length = sizeof raw;
  if (EVP_PKEY_get_raw_public_key(pkey, raw, &length) != 1)
    throw SigningError("cannot read the raw public key: " + opensslError());
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned digest_length = 0;
  EVP_Digest(raw, length, digest, &digest_length, EVP_sha256(), nullptr);
  return toHex(std::string(reinterpret_cast<const char*>(digest), 8));
}

std::string bioText(BIO* bio) {
  char* data = nullptr;
  const long n = BIO_get_mem_data(bio, &data);
  return std::string(data, static_cast<std::size_t>(n));
}

// Creates `file` with `mode`, refusing to replace anything (O_EXCL), and writes `text`.
void writeNewFile(const fs::path& file, const std::string& text, unsigned mode) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
  if (fd < 0) throw SigningError("cannot create " + file.string() + ": " + std::strerror(errno));
  ::fchmod(fd, mode);  // not narrowed or widened by the umask
  const bool ok = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size()) && ::fsync(fd) == 0;
  const int err = errno;
  ::close(fd);
  if (!ok) {
    ::unlink(file.c_str());
    throw SigningError("cannot write " + file.string() + ": " + std::strerror(err));
  }
}

// A key name is a plain file name: letters, digits, '.', '_', '-', not starting with '.'.
bool plainName(const std::string& name) {
  if (name.empty() || name.size() > 100 || name[0] == '.') return false;
  for (const char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' && c != '-') return false;
  return true;
}

// A private key file must be a regular file of this user (or root), unreadable by others.
void checkPrivateKeyFile(const fs::path& file) {
  struct stat st {};
  if (::stat(file.c_str(), &st) != 0)
    throw SigningError("cannot read private key " + file.string() + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw SigningError("private key " + file.string() + " is not a regular file");
  if (st.st_uid != ::geteuid() && st.st_uid != 0)
    throw SigningError("private key " + file.string() + " belongs to another user (uid " + std::to_string(st.st_uid) +
                       "); refusing to use it");
  if ((st.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    throw SigningError("private key " + file.string() + " has mode " + mode +
                       ": it is accessible by group or others, so it may be known to them; refusing to sign with it "
                       "(chmod 600 " + file.string() + ", and make a new key if others may have read it)");
  }
}

}  // namespace

// ---- hex ----------------------------------------------------------------------------

std::string toHex(const std::string& bytes) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  out.reserve(bytes.size() * 2);
  for (const char c : bytes) {
    const auto b = static_cast<unsigned char>(c);
    out += digits[b >> 4];
    out += digits[b & 15];
  }
  return out;
}

std::string fromHex(const std::string& hex) {
  if (hex.size() % 2 != 0) throw std::invalid_argument("hex text of odd length");
  const auto digit = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    throw std::invalid_argument(std::string("not a lowercase hex digit: '") + c + "'");
  };
  std::string out(hex.size() / 2, '\0');
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = static_cast<char>(digit(hex[2 * i]) * 16 + digit(hex[2 * i + 1]));
  return out;
}

// ---- PublicKey ----------------------------------------------------------------------

PublicKey PublicKey::fromPem(const std::string& pem, const std::string& origin) {
  Bio bio(BIO_new_mem_buf(pem.data(), static_cast<int>(pem.size())), BIO_free);
  PublicKey key;
  key.key_ = requireEd25519(PEM_read_bio_PUBKEY(bio.get(), nullptr, noPassphrase, nullptr), origin, "public key");
  key.key_id_ = keyIdOf(key.key_->pkey);
  return key;
}

PublicKey PublicKey::load(const fs::path& file) {
  return fromPem(readText(file, "public key"), "public key " + file.string());
}

std::string PublicKey::pem() const {
  Bio bio(BIO_new(BIO_s_mem()), BIO_free);
  if (PEM_write_bio_PUBKEY(bio.get(), key_->pkey) != 1) throw SigningError("cannot write a public key: " + opensslError());
  return bioText(bio.get());
}

bool PublicKey::verify(const std::string& message, const std::string& signature) const {
  if (!key_ || signature.size() != 64) return false;
  MdCtx ctx(EVP_MD_CTX_new(), EVP_MD_CTX_free);
  // Ed25519 hashes internally: no digest is named.
  if (EVP_DigestVerifyInit(ctx.get(), nullptr, nullptr, nullptr, key_->pkey) != 1) {
    ERR_clear_error();
    return false;
  }
  const int ok = EVP_DigestVerify(ctx.get(), reinterpret_cast<const unsigned char*>(signature.data()),
                                  signature.size(), reinterpret_cast<const unsigned char*>(message.data()),
                                  message.size());
  ERR_clear_error();
  return ok == 1;
}

// ---- SigningKey ---------------------------------------------------------------------

SigningKey SigningKey::generate() {
  EVP_PKEY* pkey = EVP_PKEY_Q_keygen(nullptr, nullptr, "ED25519");
  if (pkey == nullptr) throw SigningError("cannot generate an Ed25519 key: " + opensslError());
  SigningKey key;
  key.key_ = std::make_shared<detail::KeyHandle>(pkey);
  key.public_.key_ = key.key_;
  key.public_.key_id_ = keyIdOf(pkey);
  return key;
}

SigningKey SigningKey::load(const fs::path& file) {
  checkPrivateKeyFile(file);
  const std::string pem = readText(file, "private key");
  Bio bio(BIO_new_mem_buf(pem.data(), static_cast<int>(pem.size())), BIO_free);
  SigningKey key;
  key.key_ = requireEd25519(PEM_read_bio_PrivateKey(bio.get(), nullptr, noPassphrase, nullptr),
                            "private key " + file.string(), "private key");
  key.public_.key_ = key.key_;  // an Ed25519 private key carries its public half
  key.public_.key_id_ = keyIdOf(key.key_->pkey);
  return key;
}

std::string SigningKey::sign(const std::string& message) const {
  MdCtx ctx(EVP_MD_CTX_new(), EVP_MD_CTX_free);
  std::string signature(64, '\0');
  std::size_t length = signature.size();
  if (EVP_DigestSignInit(ctx.get(), nullptr, nullptr, nullptr, key_->pkey) != 1 ||
      EVP_DigestSign(ctx.get(), reinterpret_cast<unsigned char*>(signature.data()), &length,
                     reinterpret_cast<const unsigned char*>(message.data()), message.size()) != 1)
    throw SigningError("cannot sign: " + opensslError());
  signature.resize(length);
  return signature;
}

void SigningKey::writePair(const fs::path& dir, const std::string& name) const {
  if (!plainName(name))
    throw SigningError("key name \"" + name + "\" is not a plain name (letters, digits, '.', '_', '-'; not starting with '.')");
  std::error_code ec;
  if (!fs::exists(dir, ec)) {
    fs::create_directories(dir, ec);
    if (ec) throw SigningError("cannot create " + dir.string() + ": " + ec.message());
    ::chmod(dir.c_str(), 0700);
  }
  const fs::path private_file = dir / (name + ".key"), public_file = dir / (name + ".pub");
  for (const fs::path& f : {private_file, public_file})
    if (fs::exists(fs::symlink_status(f, ec)))
      throw SigningError(f.string() + " exists; refusing to overwrite a key (choose another --name or --out)");
  Bio bio(BIO_new(BIO_s_mem()), BIO_free);
  if (PEM_write_bio_PrivateKey(bio.get(), key_->pkey, nullptr, nullptr, 0, nullptr, nullptr) != 1)
    throw SigningError("cannot encode the private key: " + opensslError());
  writeNewFile(private_file, bioText(bio.get()), 0600);
  try {
    writeNewFile(public_file, public_.pem(), 0644);
  } catch (...) {
    ::unlink(private_file.c_str());  // a pair or nothing
    throw;
  }
}

// ---- TrustedKeys --------------------------------------------------------------------

TrustedKeys TrustedKeys::load(const std::vector<fs::path>& paths) {
  TrustedKeys trusted;
  for (const fs::path& path : paths) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
      std::vector<fs::path> files;
      for (fs::directory_iterator it(path, ec), end; !ec && it != end; it.increment(ec))
        if (it->path().extension() == ".pub" && it->is_regular_file()) files.push_back(it->path());
      if (ec) throw SigningError("cannot list trusted keys in " + path.string() + ": " + ec.message());
      if (files.empty()) throw SigningError("no public keys (*.pub) in " + path.string());
      for (const fs::path& f : files) trusted.add(PublicKey::load(f));
    } else if (fs::exists(path, ec)) {
      trusted.add(PublicKey::load(path));
    } else {
      throw SigningError("trusted key " + path.string() + " does not exist");
    }
  }
  if (trusted.size() == 0) throw SigningError("no trusted public keys were given");
  return trusted;
}

const PublicKey* TrustedKeys::find(const std::string& key_id) const {
  const auto it = keys_.find(key_id);
  return it == keys_.end() ? nullptr : &it->second;
}

std::vector<std::string> TrustedKeys::keyIds() const {
  std::vector<std::string> ids;
  for (const auto& [id, key] : keys_) ids.push_back(id);
  return ids;
}

}  // namespace robodiff::cache
