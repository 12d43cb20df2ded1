#include "agvslam/drivers/dds/participant.h"

#include <cctype>

namespace agvslam::drivers::dds {
namespace {

bool looks_like_address(const std::string& s) {
  for (char c : s) {
    if (std::isdigit(static_cast<unsigned char>(c)) == 0 && c != '.' && c != ':') return false;
  }
  return !s.empty();
}

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

}  // namespace

dds_return_t dds_check(dds_return_t rc, const std::string& what) {
  if (rc < 0) throw DdsError(what + ": " + dds_strretcode(rc));
  return rc;
}

std::string cyclone_config_xml(const DdsConfig& config) {
  if (!config.config_uri.empty()) return config.config_uri;
  if (config.network_interface.empty()) return {};
  const std::string attr = looks_like_address(config.network_interface) ? "address" : "name";
  // Cyclone DDS 0.10 configuration: General/Interfaces/NetworkInterface (name= or address=).
  return "<CycloneDDS><Domain id=\"any\"><General><Interfaces><NetworkInterface " + attr + "=\"" +
         xml_escape(config.network_interface) + "\"/></Interfaces></General></Domain></CycloneDDS>";
}

RosDefaultQos::RosDefaultQos(const DdsConfig& config) : qos_(dds_create_qos()) {
  dds_qset_reliability(qos_, DDS_RELIABILITY_RELIABLE, DDS_MSECS(config.max_blocking_ms));
  dds_qset_history(qos_, DDS_HISTORY_KEEP_LAST, config.history_depth);
  dds_qset_durability(qos_, DDS_DURABILITY_VOLATILE);
}

RosDefaultQos::RosDefaultQos(const DdsConfig& config, int history_depth, bool transient_local) : RosDefaultQos(config) {
  dds_qset_history(qos_, DDS_HISTORY_KEEP_LAST, history_depth);
  if (transient_local) dds_qset_durability(qos_, DDS_DURABILITY_TRANSIENT_LOCAL);
}

RosDefaultQos::~RosDefaultQos() { dds_delete_qos(qos_); }

Participant::Participant(const DdsConfig& config) {
  const auto domain = static_cast<dds_domainid_t>(config.domain_id);
  const std::string where = "DDS domain " + std::to_string(config.domain_id);
  const std::string xml = cyclone_config_xml(config);
  if (!xml.empty()) {
    const dds_entity_t d = dds_create_domain(domain, xml.c_str());
    if (d >= 0) {
      domain_ = DdsEntity(d);
    } else if (d != DDS_RETCODE_PRECONDITION_NOT_MET) {  // PRECONDITION_NOT_MET: the domain exists already
      throw DdsError(where + ": cannot create the domain with configuration " + xml + ": " + dds_strretcode(d) +
                     " (check dds.network_interface / dds.config_uri)");
    }
  }
  if (!config.security.enabled) {
    participant_ =
        DdsEntity(dds_check(dds_create_participant(domain, nullptr, nullptr), where + ": create participant"));
    return;
  }
  // Our own checks first: Cyclone's refusal is a bare return code (the reason goes to its log only).
  const EnclaveFiles files = check_enclave(config.security);
  const SecurityQos qos(config.security, files);
  const dds_entity_t p = dds_create_participant(domain, qos.get(), nullptr);
  if (p < 0) {
    throw DdsError(where + ": DDS Security refused the participant with the credentials of enclave " +
                   config.security.enclave + " in " + config.security.keystore + ": " + dds_strretcode(p) +
                   " (the files passed agvslam's checks; Cyclone DDS's log on stderr names the reason, e.g. a "
                   "permissions grant without this domain id)");
  }
  participant_ = DdsEntity(p);
}

Participant::~Participant() {
  participant_.reset();
  domain_.reset();
}

dds_entity_t Participant::create_topic(const dds_topic_descriptor_t* descriptor, const std::string& name) {
  return dds_check(dds_create_topic(participant_.get(), descriptor, name.c_str(), nullptr, nullptr),
                   "DDS topic " + name + ": create");
}

}  // namespace agvslam::drivers::dds
