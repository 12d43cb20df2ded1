#pragma once
// RAII over Cyclone DDS entities (C API): a participant in the configured domain, pinned to the configured
// network interface, and its topics with ROS 2 default QoS.

#include <dds/dds.h>

#include <stdexcept>
#include <string>

#include "agvslam/drivers/dds/dds_config.h"

namespace agvslam::drivers::dds {

// A DDS call failed; the message names the call, the domain/topic and Cyclone's return code.
class DdsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Owns one dds_entity_t (deleting it deletes its children). Move-only.
class DdsEntity {
 public:
  DdsEntity() = default;
  explicit DdsEntity(dds_entity_t handle) : handle_(handle) {}
  ~DdsEntity() { reset(); }
  DdsEntity(DdsEntity&& other) noexcept : handle_(other.handle_) { other.handle_ = 0; }
  DdsEntity& operator=(DdsEntity&& other) noexcept {
    if (this != &other) {
      reset();
      handle_ = other.handle_;
      other.handle_ = 0;
    }
    return *this;
  }
  DdsEntity(const DdsEntity&) = delete;
  DdsEntity& operator=(const DdsEntity&) = delete;

  dds_entity_t get() const { return handle_; }
  explicit operator bool() const { return handle_ > 0; }
  void reset() {
    if (handle_ > 0) dds_delete(handle_);
    handle_ = 0;
  }

 private:
  dds_entity_t handle_ = 0;
};

// Throws DdsError("<what>: <cyclone's message>") when rc < 0; returns rc otherwise.
dds_return_t dds_check(dds_return_t rc, const std::string& what);

// The Cyclone DDS XML configuration for `config` (config_uri when set, otherwise one naming network_interface;
// empty when neither is set).
std::string cyclone_config_xml(const DdsConfig& config);

// ROS 2 default QoS for a topic's writer and reader: reliable (max_blocking_ms), keep last history_depth,
// volatile.
class RosDefaultQos {
 public:
  explicit RosDefaultQos(const DdsConfig& config);
  // The same with another history depth (samples) and, when asked, transient-local durability (tf's QoS).
  RosDefaultQos(const DdsConfig& config, int history_depth, bool transient_local);
  ~RosDefaultQos();
  RosDefaultQos(const RosDefaultQos&) = delete;
  RosDefaultQos& operator=(const RosDefaultQos&) = delete;
  const dds_qos_t* get() const { return qos_; }

 private:
  dds_qos_t* qos_;
};

// A participant in config.domain_id. When the process has not used that domain yet and an interface or
// config_uri is configured, the domain is created with that configuration (and owned, i.e. deleted last). A
// domain the process already uses keeps the configuration it was created with (Cyclone allows one per domain
// and process).
class Participant {
 public:
  explicit Participant(const DdsConfig& config);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  dds_entity_t get() const { return participant_.get(); }
  // Creates a topic of `descriptor` named `name` in this participant (deleted with the participant).
  dds_entity_t create_topic(const dds_topic_descriptor_t* descriptor, const std::string& name);

 private:
  DdsEntity domain_;  // only when this object created the domain
  DdsEntity participant_;
};

}  // namespace agvslam::drivers::dds
