// The keystore layout and the dds.sec.* QoS properties of Cyclone DDS 0.10.
#include "robodiff/schema/dds_security.hpp"

#include <dlfcn.h>

#include <stdexcept>

namespace robodiff::dds_codec {

namespace fs = std::filesystem;

namespace {

const fs::path& requireFile(const fs::path& path, std::string_view what) {
  if (!fs::is_regular_file(path))
    throw std::invalid_argument("DDS security: " + std::string(what) + " " + path.string() +
                                " not found (make it with `robodiff security init|add-client`)");
  return path;
}

std::string fileUri(const fs::path& path) { return "file:" + fs::absolute(path).string(); }

}  // namespace

std::string DdsSecurity::describe() const {
  const fs::path identity_dir = certificate.parent_path();
  return "identity " + identity_dir.filename().string() + " of keystore " +
         identity_dir.parent_path().parent_path().string();
}

DdsSecurity keystoreIdentity(const fs::path& keystore, std::string_view name) {
  if (name.empty() || name.find('/') != std::string_view::npos)
    throw std::invalid_argument("DDS security: identity name '" + std::string(name) +
                                "' must be non-empty and contain no '/'");
  const fs::path identity = keystore / "identities" / name;
  DdsSecurity s;
  s.identity_ca = requireFile(keystore / "ca.cert.pem", "CA certificate");
  s.permissions_ca = s.identity_ca;
  s.governance = requireFile(keystore / "governance.p7s", "signed governance");
  s.certificate = requireFile(identity / "cert.pem", "identity certificate");
  s.private_key = requireFile(identity / "key.pem", "private key");
  s.permissions = requireFile(identity / "permissions.p7s", "signed permissions");
  return s;
}

DdsSecurity securityFromSpec(std::string_view spec) {
  fs::path path(spec);
  if (!path.has_filename()) path = path.parent_path();  // trailing '/'
  if (path.filename().empty() || !path.has_parent_path())
    throw std::invalid_argument("DDS security '" + std::string(spec) +
                                "': expected <keystore>/<identity>, e.g. /etc/robodiff/keystore/alice");
  return keystoreIdentity(path.parent_path(), path.filename().string());
}

fs::path securityPluginDir() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&dds_create_participant), &info) == 0 || info.dli_fname == nullptr)
    throw std::runtime_error("DDS security: cannot locate the loaded libddsc (dladdr failed)");
  const fs::path libdir = fs::canonical(info.dli_fname).parent_path();
  for (const fs::path& dir : {libdir / "libddsc0debian", libdir})
    if (fs::exists(dir / "libdds_security_auth.so")) return dir;
  throw std::runtime_error("DDS security: libdds_security_auth.so is neither in " + libdir.string() + " nor in " +
                           (libdir / "libddsc0debian").string() + " (install Cyclone DDS with its security plugins)");
}

void applySecurity(dds_qos_t* qos, const DdsSecurity& s) {
  const fs::path plugins = securityPluginDir();
  struct Plugin {
    const char* prefix;
    const char* file;
    const char* init;
    const char* finalize;
  };
  for (const Plugin& p : {Plugin{"dds.sec.auth", "libdds_security_auth.so", "init_authentication", "finalize_authentication"},
                          Plugin{"dds.sec.access", "libdds_security_ac.so", "init_access_control", "finalize_access_control"},
                          Plugin{"dds.sec.crypto", "libdds_security_crypto.so", "init_crypto", "finalize_crypto"}}) {
    const std::string prefix = p.prefix;
    dds_qset_prop(qos, (prefix + ".library.path").c_str(), (plugins / p.file).c_str());
    dds_qset_prop(qos, (prefix + ".library.init").c_str(), p.init);
    dds_qset_prop(qos, (prefix + ".library.finalize").c_str(), p.finalize);
  }
  dds_qset_prop(qos, "dds.sec.auth.identity_ca", fileUri(s.identity_ca).c_str());
  dds_qset_prop(qos, "dds.sec.auth.identity_certificate", fileUri(s.certificate).c_str());
  dds_qset_prop(qos, "dds.sec.auth.private_key", fileUri(s.private_key).c_str());
  dds_qset_prop(qos, "dds.sec.access.permissions_ca", fileUri(s.permissions_ca).c_str());
  dds_qset_prop(qos, "dds.sec.access.governance", fileUri(s.governance).c_str());
  dds_qset_prop(qos, "dds.sec.access.permissions", fileUri(s.permissions).c_str());
}

}  // namespace robodiff::dds_codec
