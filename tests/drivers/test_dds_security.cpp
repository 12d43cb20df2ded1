// DDS Security with a keystore made by deploy/make-keystore.sh (SROS2 layout), Cyclone DDS's built-in plugins.
//  - Start-up checks, in this process: a tampered permissions file, a certificate of another CA or one that has
//    expired, a missing or foreign key, a permissions grant that has expired are refused with an InputError naming the
//    file; an enclave whose permissions do not allow publishing the pose cannot create the pose writer.
//  - Two and more processes in a private network namespace (unshare -n, lo up), with agvslam-pose-replay as the
//    daemon's publisher and agvslam-echo as subscribers: an authenticated reader receives every sample; a reader
//    without credentials and one with credentials of another CA receive nothing; a publisher without credentials
//    writing to what agvslamd subscribes to (rt/<ns>/in/*) is not delivered, while an enclave permitted to
//    publish there is.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "agvslam/core/error.h"
#include "agvslam/drivers/dds/publisher.h"
#include "common/test_data.h"
#include "dds_test_util.h"

namespace {

using namespace agvslam::drivers::dds;
using agvslam::test::read_json_lines;
using agvslam::test::run_command;
using agvslam::test::tool_path;
namespace fs = std::filesystem;

const std::string kScript = std::string(AGVSLAM_SOURCE_DIR) + "/deploy/make-keystore.sh";

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_text(const std::string& path, const std::string& text) {
  fs::remove(path);  // may be a link into the keystore
  std::ofstream(path, std::ios::binary) << text;
}

// Two keystores made once: `ks` with the daemon, reader and input enclaves, `other` (another CA) with a reader.
class DdsSecurity : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = agvslam::test::make_temp_dir("agvslam-ddssec");
    std::string out;
    const int rc = run_command(kScript + " " + dir_ + "/ks /agvslam/agvslamd:daemon /agvslam/reader:reader " +
                                   "/agvslam/in:input && " + kScript + " " + dir_ + "/other /agvslam/reader:reader",
                               &out);
    ASSERT_EQ(rc, 0) << out;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  // A copy of the main keystore to spoil (links kept as links).
  static std::string copy_keystore(const std::string& name) {
    const std::string to = dir_ + "/" + name;
    fs::remove_all(to);
    fs::copy(dir_ + "/ks", to, fs::copy_options::recursive | fs::copy_options::copy_symlinks);
    return to;
  }

  static DdsConfig config(const std::string& keystore, const std::string& enclave, int domain_offset) {
    DdsConfig c;
    c.domain_id = 20 + static_cast<int>((getpid() + domain_offset) % 200);
    c.network_interface = "lo";
    c.security.enabled = true;
    c.security.keystore = keystore;
    c.security.enclave = enclave;
    return c;
  }

  // The InputError a publisher with `c` raises at construction ("" when none).
  static std::string start_up_error(const DdsConfig& c) {
    try {
      DdsPosePublisher pub(c);
    } catch (const agvslam::InputError& e) {
      return e.what();
    }
    return "";
  }

  static std::string dir_;
};
std::string DdsSecurity::dir_;

TEST_F(DdsSecurity, ScriptMakesTheSros2LayoutAndEveryEnclavePassesTheChecks) {
  for (const char* f : {"public/ca.cert.pem", "public/identity_ca.cert.pem", "public/permissions_ca.cert.pem",
                        "private/ca.key.pem", "private/identity_ca.key.pem", "private/permissions_ca.key.pem",
                        "enclaves/governance.xml", "enclaves/governance.p7s"}) {
    EXPECT_TRUE(fs::is_regular_file(dir_ + "/ks/" + f)) << f;
  }
  for (const char* enclave : {"/agvslam/agvslamd", "/agvslam/reader", "/agvslam/in"}) {
    DdsSecurityConfig c;
    c.enabled = true;
    c.keystore = dir_ + "/ks";
    c.enclave = enclave;
    const EnclaveFiles f = check_enclave(c);
    for (const std::string& path :
         {f.identity_ca, f.certificate, f.private_key, f.permissions_ca, f.governance, f.permissions}) {
      EXPECT_TRUE(fs::is_regular_file(path)) << path;
    }
    EXPECT_NE(read_text(fs::path(f.permissions).replace_extension(".xml").string())
                  .find("<subject_name>CN=" + std::string(enclave) + "</subject_name>"),
              std::string::npos)
        << enclave;
  }
  // The daemon publishes its topics and reads only its inputs; the reader publishes nothing of agvslam's.
  const std::string daemon = read_text(dir_ + "/ks/enclaves/agvslam/agvslamd/permissions.xml");
  EXPECT_NE(daemon.find("<publish><topics><topic>rt/agvslam/*</topic><topic>rt/tf</topic><topic>rt/tf_static</topic>"
                        "</topics></publish>"),
            std::string::npos);
  EXPECT_NE(daemon.find("<subscribe><topics><topic>rt/agvslam/in/*</topic></topics></subscribe>"), std::string::npos);
  const std::string reader = read_text(dir_ + "/ks/enclaves/agvslam/reader/permissions.xml");
  EXPECT_EQ(reader.find("<topic>rt/agvslam/"), reader.find("<subscribe>") + std::string("<subscribe><topics>").size());
}

TEST_F(DdsSecurity, TamperedPermissionsAreRefusedAtStartUpNamingTheFile) {
  const std::string ks = copy_keystore("tampered");
  const std::string p7s = ks + "/enclaves/agvslam/agvslamd/permissions.p7s";
  std::string text = read_text(p7s);
  const std::string granted = "<topic>rt/agvslam/in/*</topic>";
  ASSERT_NE(text.find(granted), std::string::npos);
  text.replace(text.find(granted), granted.size(), "<topic>*</topic>");  // subscribe to everything
  write_text(p7s, text);

  const std::string error = start_up_error(config(ks, "/agvslam/agvslamd", 0));
  EXPECT_NE(error.find(p7s), std::string::npos) << error;
  EXPECT_NE(error.find("signature does not verify"), std::string::npos) << error;

  // The same through a tool: exit 2 (bad input) with the message, before any DDS traffic.
  std::string out;
  EXPECT_EQ(run_command(tool_path("agvslam-pose-replay") + " --synthetic 1 --dds --interface lo --keystore " + ks +
                            " --enclave /agvslam/agvslamd",
                        &out),
            2)
      << out;
  EXPECT_NE(out.find(p7s + ": expected this enclave's permissions document signed by the permissions CA"),
            std::string::npos)
      << out;
}

TEST_F(DdsSecurity, CertificateOfAnotherCaIsRefusedAtStartUp) {
  const std::string ks = copy_keystore("other_ca_cert");
  const std::string enclave = ks + "/enclaves/agvslam/reader/";
  fs::copy_file(dir_ + "/other/enclaves/agvslam/reader/cert.pem", enclave + "cert.pem",
                fs::copy_options::overwrite_existing);
  fs::copy_file(dir_ + "/other/enclaves/agvslam/reader/key.pem", enclave + "key.pem",
                fs::copy_options::overwrite_existing);
  const std::string error = start_up_error(config(ks, "/agvslam/reader", 1));
  EXPECT_NE(error.find(enclave + "cert.pem: expected a certificate issued by the identity CA"), std::string::npos)
      << error;
  EXPECT_NE(error.find("unable to get local issuer certificate"), std::string::npos) << error;
}

TEST_F(DdsSecurity, ExpiredCertificateIsRefusedAtStartUp) {
  const std::string ks = copy_keystore("expired_cert");
  const std::string enclave = ks + "/enclaves/agvslam/reader/";
  std::string out;
  // The enclave's own key, certified by the keystore's CA until yesterday.
  ASSERT_EQ(run_command("openssl req -new -key " + enclave + "key.pem -subj '/CN=\\/agvslam\\/reader' -out " + enclave +
                            "req.pem && openssl x509 -req -days -1 -in " + enclave + "req.pem -CA " + ks +
                            "/public/ca.cert.pem -CAkey " + ks + "/private/ca.key.pem -set_serial 7 -out " + enclave +
                            "cert.pem",
                        &out),
            0)
      << out;
  const std::string error = start_up_error(config(ks, "/agvslam/reader", 5));
  EXPECT_NE(error.find(enclave + "cert.pem: expected a certificate issued by the identity CA"), std::string::npos)
      << error;
  EXPECT_NE(error.find("certificate has expired"), std::string::npos) << error;
}

TEST_F(DdsSecurity, MissingOrForeignKeyIsRefusedAtStartUp) {
  const std::string ks = copy_keystore("bad_key");
  const std::string key = ks + "/enclaves/agvslam/reader/key.pem";
  fs::copy_file(ks + "/enclaves/agvslam/in/key.pem", key, fs::copy_options::overwrite_existing);
  std::string error = start_up_error(config(ks, "/agvslam/reader", 2));
  EXPECT_NE(error.find(key + ": expected the private key of"), std::string::npos) << error;

  fs::remove(key);
  error = start_up_error(config(ks, "/agvslam/reader", 2));
  EXPECT_NE(error.find(key + ": expected this enclave's private key"), std::string::npos) << error;
  EXPECT_NE(error.find("missing"), std::string::npos) << error;

  error = start_up_error(config(ks, "/agvslam/nobody", 2));
  EXPECT_NE(error.find("/enclaves/agvslam/nobody: expected the directory of enclave /agvslam/nobody"),
            std::string::npos)
      << error;
}

TEST_F(DdsSecurity, ExpiredPermissionsGrantIsRefusedAtStartUp) {
  const std::string ks = copy_keystore("expired");
  const std::string enclave = ks + "/enclaves/agvslam/reader/";
  std::string xml = read_text(enclave + "permissions.xml");
  const std::size_t a = xml.find("<validity>");
  const std::size_t b = xml.find("</validity>");
  ASSERT_NE(a, std::string::npos);
  xml.replace(a, b - a,
              "<validity><not_before>2020-01-01T00:00:00</not_before><not_after>2021-01-01T00:00:00</not_after>");
  write_text(enclave + "permissions.xml", xml);
  std::string out;
  ASSERT_EQ(
      run_command("openssl smime -sign -text -md sha256 -in " + enclave + "permissions.xml -out " + enclave +
                      "permissions.p7s -signer " + ks + "/public/ca.cert.pem -inkey " + ks + "/private/ca.key.pem",
                  &out),
      0)
      << out;
  const std::string error = start_up_error(config(ks, "/agvslam/reader", 3));
  EXPECT_NE(error.find(enclave + "permissions.p7s: expected the grant for CN=/agvslam/reader to be valid now; it is "
                                 "valid from 2020-01-01T00:00:00 to 2021-01-01T00:00:00"),
            std::string::npos)
      << error;
}

TEST_F(DdsSecurity, EnclaveWithoutPublishPermissionCannotCreateThePoseWriter) {
  try {
    DdsPosePublisher pub(config(dir_ + "/ks", "/agvslam/reader", 4));
    FAIL() << "the reader enclave created a pose writer";
  } catch (const DdsError& e) {
    EXPECT_NE(std::string(e.what()).find("DDS writer rt/agvslam/"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Not Allowed By Security"), std::string::npos) << e.what();
  }
}

// ---- several processes in a network namespace ----

// The samples per topic an agvslam-echo --json output received, and its summary.
struct Received {
  std::map<std::string, std::vector<nlohmann::json>> per_topic;
  nlohmann::json summary;
};
Received read_echo(const std::string& path) {
  Received r;
  for (const auto& line : read_json_lines(path)) {
    if (line.contains("summary")) {
      r.summary = line.at("summary");
    } else {
      r.per_topic[line.at("topic").get<std::string>()].push_back(line.at("msg"));
    }
  }
  return r;
}

// What agvslam-pose-replay --json handed to DDS, per topic.
std::map<std::string, std::vector<nlohmann::json>> read_sent(const std::string& path) {
  std::map<std::string, std::vector<nlohmann::json>> sent;
  for (const auto& line : read_json_lines(path)) {
    if (!line.contains("dds")) continue;
    for (const char* topic : {"pose", "odom", "status"}) sent[topic].push_back(line.at("dds").at(topic));
  }
  return sent;
}

TEST_F(DdsSecurity, OnlyAuthenticatedReadersReceiveThePose) {
  REQUIRE_NETNS(ns);
  const int n = 100;
  const std::string d = dir_ + "/readers";
  fs::create_directories(d);
  const std::string echo = tool_path("agvslam-echo") + " --json --interface lo ";
  // Three readers start first; the publisher waits for the authenticated one, then sends n samples per topic
  // (1 s at 100 Hz) while the others listen for 6 s.
  const std::string script = "ip link set lo up && (" + echo + "--keystore " + dir_ +
                             "/ks --enclave /agvslam/reader --count " + std::to_string(3 * n) + " --timeout 30 > " + d +
                             "/ok.jsonl 2> " + d + "/ok.err & " + echo + "--count 1 --timeout 6 > " + d +
                             "/plain.jsonl 2> " + d + "/plain.err & " + echo + "--keystore " + dir_ +
                             "/other --enclave /agvslam/reader --count 1 --timeout 6 > " + d + "/other_ca.jsonl 2> " +
                             d + "/other_ca.err & " + tool_path("agvslam-pose-replay") + " --synthetic " +
                             std::to_string(n) + " --rate 100 --dds --interface lo --keystore " + dir_ +
                             "/ks --enclave /agvslam/agvslamd " + "--wait-subscribers 1 --wait-timeout 30 --json > " +
                             d + "/sent.jsonl 2> " + d + "/sent.err; echo replay=$?; wait)";
  std::string out;
  ASSERT_EQ(run_command(ns + " sh -c '" + script + "'", &out), 0) << out;
  ASSERT_NE(out.find("replay=0"), std::string::npos) << out << read_text(d + "/sent.err");

  const auto sent = read_sent(d + "/sent.jsonl");
  const Received ok = read_echo(d + "/ok.jsonl");
  for (const char* topic : {"pose", "odom", "status"}) {
    ASSERT_EQ(sent.at(topic).size(), static_cast<std::size_t>(n)) << topic;
    EXPECT_EQ(ok.per_topic.count(topic) != 0 ? ok.per_topic.at(topic) : std::vector<nlohmann::json>{}, sent.at(topic))
        << topic << ": the authenticated reader's samples\n"
        << read_text(d + "/ok.err");
  }
  for (const char* who : {"plain", "other_ca"}) {
    const Received r = read_echo(d + "/" + who + ".jsonl");
    ASSERT_TRUE(r.summary.contains("received")) << who << "\n" << read_text(d + "/" + who + ".err");
    EXPECT_EQ(r.summary.at("received").get<long>(), 0) << who;
    EXPECT_TRUE(r.summary.at("timed_out").get<bool>()) << who << ": listened to the end";
    EXPECT_TRUE(r.per_topic.empty()) << who;
  }
}

TEST_F(DdsSecurity, PublisherWithoutCredentialsCannotInjectIntoTheDaemonsInputs) {
  REQUIRE_NETNS(ns);
  const int n = 100;
  const std::string d = dir_ + "/inject";
  fs::create_directories(d);
  const std::string replay = tool_path("agvslam-pose-replay") + " --synthetic " + std::to_string(n) +
                             " --rate 100 --dds --interface lo --namespace agvslam/in --json ";
  // agvslamd's enclave reads rt/agvslam/in/*; a plain publisher writes there for 1 s (stamped now), then the
  // input enclave writes the same drive (stamped with the synthetic times). The reader stops after 3n samples:
  // had any plain sample been delivered, it would be among them.
  const std::string script =
      "ip link set lo up && (" + tool_path("agvslam-echo") + " --json --interface lo --namespace agvslam/in " +
      "--keystore " + dir_ + "/ks --enclave /agvslam/agvslamd --count " + std::to_string(3 * n) + " --timeout 30 > " +
      d + "/daemon.jsonl 2> " + d + "/daemon.err & sleep 1; " + replay + "--stamp now > " + d + "/plain.jsonl 2> " + d +
      "/plain.err; echo plain=$?; " + replay + "--stamp source --keystore " + dir_ +
      "/ks --enclave /agvslam/in --wait-subscribers 1 --wait-timeout 30 > " + d + "/input.jsonl 2> " + d +
      "/input.err; echo input=$?; wait $!; echo echo=$?)";
  std::string out;
  ASSERT_EQ(run_command(ns + " sh -c '" + script + "'", &out), 0) << out;
  EXPECT_NE(out.find("plain=0"), std::string::npos) << out;  // the plain writer believed it published
  ASSERT_NE(out.find("input=0"), std::string::npos) << out << read_text(d + "/input.err");
  EXPECT_NE(out.find("echo=0"), std::string::npos) << out << read_text(d + "/daemon.err");

  const auto plain = read_sent(d + "/plain.jsonl");
  const auto input = read_sent(d + "/input.jsonl");
  const Received got = read_echo(d + "/daemon.jsonl");
  for (const char* topic : {"pose", "odom", "status"}) {
    ASSERT_EQ(plain.at(topic).size(), static_cast<std::size_t>(n)) << topic;
    ASSERT_NE(plain.at(topic).front(), input.at(topic).front()) << topic << ": the two drives must differ";
    EXPECT_EQ(got.per_topic.count(topic) != 0 ? got.per_topic.at(topic) : std::vector<nlohmann::json>{},
              input.at(topic))
        << topic << ": only the permitted publisher's samples";
  }
}

}  // namespace
