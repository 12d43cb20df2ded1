#pragma once
// DDS Security (OMG DDS Security 1.1 with Cyclone DDS's built-in plugins): the participant authenticates with an
// X.509 identity, is admitted by signed governance and permissions documents, and encrypts discovery and data.
// The credentials come from a keystore laid out as ROS 2's SROS2 makes it (deploy/make-keystore.sh):
//
//   <keystore>/enclaves/<enclave>/{identity_ca.cert.pem, cert.pem, key.pem, permissions_ca.cert.pem,
//                                  governance.p7s, permissions.p7s}
//
// Every file is checked here before Cyclone sees it (present, parsable, certificate issued by the identity CA
// and valid now, key matching the certificate, documents signed by the permissions CA, a permissions grant for
// the certificate's subject that is valid now), so a bad keystore is refused at start-up with an InputError
// naming the file and what was expected; Cyclone's own refusals are reported with its return code.

#include <dds/dds.h>

#include <string>
#include <vector>

#include "agvslam/core/param_table.h"

namespace agvslam::drivers::dds {

struct DdsSecurityConfig {
  // false: plain DDS (anyone on the network can read the pose and publish on the topics).
  bool enabled = false;
  // The SROS2 keystore directory (ROS_SECURITY_KEYSTORE of a ROS 2 node).
  std::string keystore;
  // The enclave whose credentials this participant uses (ROS_SECURITY_ENCLAVE_OVERRIDE of a ROS 2 node).
  std::string enclave = "/agvslam/agvslamd";
  // Directory of Cyclone DDS's security plugins (libdds_security_{auth,ac,crypto}.so); empty: the one found
  // when agvslam was built (Debian installs them outside the loader's search path).
  std::string plugin_dir;

  void validate(const std::string& source) const;
  std::string describe() const;
};

// The settings of the `dds_security` section.
const params::Table<DdsSecurityConfig>& dds_security_params();

// The plugin directory found when agvslam was built ("" when none was).
std::string default_security_plugin_dir();

// The files of one enclave (absolute paths).
struct EnclaveFiles {
  std::string identity_ca;     // identity_ca.cert.pem
  std::string certificate;     // cert.pem
  std::string private_key;     // key.pem
  std::string permissions_ca;  // permissions_ca.cert.pem
  std::string governance;      // governance.p7s
  std::string permissions;     // permissions.p7s
};
EnclaveFiles enclave_files(const DdsSecurityConfig& config);

// Checks every file of the enclave and the plugins (see the top of this file); throws InputError(file, "",
// "expected ...") for the first that fails. Returns the files.
EnclaveFiles check_enclave(const DdsSecurityConfig& config);

// Participant QoS with the DDS Security properties (dds.sec.auth.*, dds.sec.access.*, dds.sec.crypto.*) for the
// checked files. Owns the QoS.
class SecurityQos {
 public:
  SecurityQos(const DdsSecurityConfig& config, const EnclaveFiles& files);
  ~SecurityQos();
  SecurityQos(const SecurityQos&) = delete;
  SecurityQos& operator=(const SecurityQos&) = delete;
  const dds_qos_t* get() const { return qos_; }

 private:
  dds_qos_t* qos_;
};

}  // namespace agvslam::drivers::dds
