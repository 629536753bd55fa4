// The keystore: openssl for keys, certificates and S/MIME signatures; the governance and
// permissions XML (OMG DDS Security 1.1) written here.
#include "robodiff/client/dds_keystore.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <chrono>
#include <ctime>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "robodiff/process/program_path.hpp"
#include "robodiff/process/spawn.hpp"
#include "robodiff/schema/dds_partitions.hpp"

namespace robodiff::client {

namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void writeFile(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::trunc);
  out << text;
  if (!out.flush()) throw std::runtime_error("cannot write " + path.string());
}

// The openssl child: keys it writes readable by nobody else, not even for a moment;
// stdout and stderr into the log the parent opened (async-signal-safe calls only).
void setUpOpenssl(const void* context, int /*report_fd*/) {
  const int log_fd = *static_cast<const int*>(context);
  umask(077);
  dup2(log_fd, 1);
  dup2(log_fd, 2);
}

// Runs `openssl args...` with its output in `log`; throws with that output on failure.
void openssl(const std::vector<std::string>& args, const fs::path& log, std::string_view step) {
  const std::string program = process::findProgram("openssl");
  if (program.empty())
    throw std::runtime_error(std::string(step) + ": the openssl command was not found in PATH (apt-get install openssl)");
  std::vector<char*> argv{const_cast<char*>(program.c_str())};
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const int log_fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (log_fd < 0) throw std::runtime_error(std::string(step) + ": cannot write " + log.string() + ": " + std::strerror(errno));
  const process::Spawned child = process::spawn(program.c_str(), argv.data(), setUpOpenssl, &log_fd);
  close(log_fd);
  if (!child.ok()) throw std::runtime_error(std::string(step) + ": " + child.error);
  int status = 0;
  while (waitpid(child.pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
  throw std::runtime_error(std::string(step) + ": openssl failed: " + slurp(log).substr(0, 2000));
}

void newKey(const fs::path& key, const fs::path& log) {
  openssl({"genpkey", "-algorithm", "EC", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-out", key.string()}, log,
          "generating the ECDSA P-256 key " + key.string());
  fs::permissions(key, fs::perms::owner_read | fs::perms::owner_write);
}

// "/CN=alice/O=robodiff" from "CN=alice,O=robodiff".
std::string opensslSubject(const std::string& subject) {
  std::string out = "/" + subject;
  for (char& c : out)
    if (c == ',') c = '/';
  return out;
}

std::string randomSerial() {
  std::random_device device;
  std::ostringstream hex;
  hex << "0x" << std::hex << (std::uint64_t(device()) << 32 | device()) << device();
  return hex.str();
}

void sign(const fs::path& dir, const fs::path& xml, const fs::path& log) {
  fs::path p7s = xml;
  p7s.replace_extension(".p7s");
  openssl({"smime", "-sign", "-text", "-in", xml.string(), "-out", p7s.string(), "-signer",
           (dir / "ca.cert.pem").string(), "-inkey", (dir / "private" / "ca.key.pem").string()},
          log, "signing " + xml.string());
}

// "2036-11-23T18:00:00" (UTC), `days` from now.
std::string isoDate(int days) {
  const std::time_t t = std::time(nullptr) + std::time_t(days) * 86400;
  std::tm utc{};
  gmtime_r(&t, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &utc);
  return text;
}

// Every DDS domain id the access-control plugin accepts (0 .. 230).
const char* kDomains = "<domains><id_range><min>0</min><max>230</max></id_range></domains>";

// Every topic: discovery, liveliness and data encrypted, reads and writes checked against
// the permissions; metadata encrypted only on request.
std::string topicAccessRulesXml(bool protect_metadata) {
  return std::string(R"(<topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>)") +
         (protect_metadata ? "ENCRYPT" : "NONE") + R"(</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>)";
}

std::string governanceXml(const KeystoreOptions& options) {
  return std::string(R"(<?xml version="1.0" encoding="UTF-8"?>
<!-- robodiff DDS Security governance: every participant must authenticate; discovery,
     liveliness and every topic's data are encrypted (AES-GCM: authenticated encryption);
     only permitted identities may read or write a topic. Metadata (the RTPS submessages
     around the data: heartbeats, acknowledgements) is protected only when made with
     `robodiff security init --protect-metadata` (deploy/security.md: it costs latency). -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      )") + kDomains + R"(
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>NONE</rtps_protection_kind>
      )" + topicAccessRulesXml(options.protect_metadata) + R"(
    </domain_rule>
  </domain_access_rules>
</dds>
)";
}

// A publish or subscribe rule for one topic, in the given partitions (none: the default one).
std::string topicRule(const char* action, const std::string& topic, const std::vector<std::string>& partitions) {
  std::string rule = std::string("<") + action + "><topics><topic>" + topic + "</topic></topics>";
  if (!partitions.empty()) {
    rule += "<partitions>";
    for (const std::string& p : partitions) rule += "<partition>" + p + "</partition>";
    rule += "</partitions>";
  }
  return rule + "</" + action + ">";
}

// A client publishes requests and reads replies only in its own caller partition (the
// server reads the partition as the caller's identity and answers there:
// dds_partitions.hpp); the server reads requests and writes replies in all of them.
std::string permissionsXml(std::string_view name, IdentityRole role, const KeystoreOptions& options) {
  const std::string request = options.service_name + "_request", reply = options.service_name + "_reply";
  const std::vector<std::string> partitions =
      role == IdentityRole::Server ? dds_codec::serverRequestPartitions()
                                   : std::vector{dds_codec::callerPartition(name, role == IdentityRole::Operator)};
  const bool server = role == IdentityRole::Server;
  std::string rules;
  if (server)  // first: permittedCallerPartition takes the first caller partition granted
    for (const std::string& service : options.also_calls) {
      const std::vector<std::string> own{dds_codec::callerPartition(name, false)};
      rules += topicRule("publish", service + "_request", own) + "\n        " +
               topicRule("subscribe", service + "_reply", own) + "\n        ";
    }
  rules += topicRule("publish", server ? reply : request, partitions) + "\n        " +
           topicRule("subscribe", server ? request : reply, partitions);
  std::ostringstream xml;
  xml << R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name=")" << name << R"(">
      <subject_name>)" << identitySubject(name, role) << R"(</subject_name>
      <validity><not_before>)" << isoDate(-1) << "</not_before><not_after>" << isoDate(options.valid_days)
      << R"(</not_after></validity>
      <allow_rule>
        )" << kDomains << R"(
        )" << rules << R"(
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
)";
  return xml.str();
}

void checkName(std::string_view name) {
  if (name.empty() || name.size() > 64) throw std::invalid_argument("identity name must have 1 to 64 characters");
  for (char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.')
      throw std::invalid_argument("identity name '" + std::string(name) +
                                  "': only letters, digits, '-', '_' and '.' are allowed");
}

}  // namespace

std::string identitySubject(std::string_view name, IdentityRole role) {
  return "CN=" + std::string(name) + (role == IdentityRole::Operator ? ",OU=operators" : "") + ",O=robodiff";
}

void initKeystore(const fs::path& dir, std::string_view server_name, const KeystoreOptions& options) {
  checkName(server_name);
  if (fs::exists(dir / "ca.cert.pem"))
    throw std::runtime_error("keystore " + dir.string() + " already exists (ca.cert.pem); use another directory");
  fs::create_directories(dir / "private");
  fs::create_directories(dir / "identities");
  fs::permissions(dir / "private", fs::perms::owner_all);
  const fs::path log = dir / "private" / "openssl.log";
  const fs::path key = dir / "private" / "ca.key.pem";
  newKey(key, log);
  openssl({"req", "-x509", "-new", "-sha256", "-key", key.string(), "-subj", "/CN=robodiff CA/O=robodiff", "-days",
           std::to_string(options.valid_days), "-out", (dir / "ca.cert.pem").string()},
          log, "making the CA certificate");
  writeFile(dir / "governance.xml", governanceXml(options));
  sign(dir, dir / "governance.xml", log);
  fs::remove(log);
  addIdentity(dir, server_name, IdentityRole::Server, options);
}

void addIdentity(const fs::path& dir, std::string_view name, IdentityRole role, const KeystoreOptions& options) {
  checkName(name);
  if (!fs::exists(dir / "private" / "ca.key.pem"))
    throw std::invalid_argument("no keystore CA key at " + (dir / "private" / "ca.key.pem").string() +
                                " (run `robodiff security init " + dir.string() + "` first)");
  const fs::path identity = dir / "identities" / name;
  if (fs::exists(identity)) throw std::invalid_argument("identity " + identity.string() + " already exists");
  fs::create_directories(identity);
  const fs::path log = dir / "private" / "openssl.log";
  newKey(identity / "key.pem", log);
  const std::string subject = identitySubject(name, role);
  openssl({"req", "-new", "-sha256", "-key", (identity / "key.pem").string(), "-subj", opensslSubject(subject), "-out",
           (identity / "cert.csr").string()},
          log, "making the certificate request of " + std::string(name));
  openssl({"x509", "-req", "-sha256", "-in", (identity / "cert.csr").string(), "-CA", (dir / "ca.cert.pem").string(),
           "-CAkey", (dir / "private" / "ca.key.pem").string(), "-set_serial", randomSerial(), "-days",
           std::to_string(options.valid_days), "-out", (identity / "cert.pem").string()},
          log, "signing the certificate of " + std::string(name));
  fs::remove(identity / "cert.csr");
  writeFile(identity / "permissions.xml", permissionsXml(name, role, options));
  sign(dir, identity / "permissions.xml", log);
  fs::remove(log);
}

}  // namespace robodiff::client
