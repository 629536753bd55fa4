// Ed25519 keys and signatures for cache artifacts that travel between hosts (OpenSSL 3).
//
// A key pair lives in two PEM files: NAME.key (the private key, PKCS#8, mode 0600; one
// readable by group or others is refused, as ssh refuses such keys) and NAME.pub (the
// public key, SubjectPublicKeyInfo). A key is named by its key id: the first 16 hex
// digits of the SHA-256 of the 32-byte raw public key. A host trusts the public keys it
// was given (TrustedKeys) and nothing else.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace robodiff::cache {

// A key file that is missing, malformed, not Ed25519, or unsafe (its message says which).
class SigningError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

namespace detail {
struct KeyHandle;  // an owned EVP_PKEY
}

// A public key: checks signatures.
class PublicKey {
 public:
  // Reads a PEM public key file. Throws SigningError naming the file.
  static PublicKey load(const std::filesystem::path& file);
  // Parses PEM text; `origin` names it in errors.
  static PublicKey fromPem(const std::string& pem, const std::string& origin);

  const std::string& keyId() const { return key_id_; }
  std::string pem() const;
  // Whether `signature` (64 raw bytes) is this key's Ed25519 signature of `message`.
  bool verify(const std::string& message, const std::string& signature) const;

 private:
  std::shared_ptr<detail::KeyHandle> key_;
  std::string key_id_;
  friend class SigningKey;
};

// A private key: makes signatures.
class SigningKey {
 public:
  static SigningKey generate();
  // Reads a PEM private key file. Throws SigningError when the file is another user's or
  // readable by group or others (naming its mode and the chmod that fixes it), is
  // encrypted, or is not an Ed25519 key.
  static SigningKey load(const std::filesystem::path& file);

  const std::string& keyId() const { return public_.keyId(); }
  const PublicKey& publicKey() const { return public_; }
  // The 64-byte Ed25519 signature of `message`.
  std::string sign(const std::string& message) const;
  // Writes DIR/NAME.key (0600) and DIR/NAME.pub (0644); DIR is created (0700) when
  // missing. Refuses (SigningError) when either file exists or NAME is not a plain name.
  void writePair(const std::filesystem::path& dir, const std::string& name) const;

 private:
  std::shared_ptr<detail::KeyHandle> key_;
  PublicKey public_;
};

// The public keys a host accepts signatures from, by key id.
class TrustedKeys {
 public:
  // Each path is a public key file or a directory whose *.pub files are read. Throws
  // SigningError when a path is missing, a file is not a public key, or nothing is found.
  static TrustedKeys load(const std::vector<std::filesystem::path>& paths);

  void add(const PublicKey& key) { keys_.insert_or_assign(key.keyId(), key); }
  // The key with this id, or nullptr.
  const PublicKey* find(const std::string& key_id) const;
  std::size_t size() const { return keys_.size(); }
  std::vector<std::string> keyIds() const;

 private:
  std::map<std::string, PublicKey> keys_;
};

// Lowercase hex of bytes, and back (throws std::invalid_argument on a bad digit or length).
std::string toHex(const std::string& bytes);
std::string fromHex(const std::string& hex);

}  // namespace robodiff::cache
