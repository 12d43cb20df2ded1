#include "agvslam/drivers/dds/publisher.h"

namespace agvslam::drivers::dds {

namespace {

// One tf2_msgs/TFMessage of n transforms (borrowed, not freed by Cyclone).
bool write_transforms(dds_entity_t writer, TransformMsg* transforms, uint32_t n) {
  TfMsg m{};
  m.transforms._length = m.transforms._maximum = n;
  m.transforms._buffer = transforms;
  m.transforms._release = false;
  return dds_write(writer, &m) >= 0;
}

}  // namespace

const char* to_string(Topic topic) {
  switch (topic) {
    case Topic::kPose:
      return "pose";
    case Topic::kOdom:
      return "odom";
    case Topic::kStatus:
      return "status";
    case Topic::kTf:
      return "tf";
    case Topic::kTfStatic:
      return "tf_static";
  }
  return "unknown";
}

DdsPosePublisher::DdsPosePublisher(const DdsConfig& config, bool start_thread)
    : config_(config),
      frames_{config.map_frame_id, config.odom_frame_id, config.base_frame_id},
      participant_((config.validate("DdsConfig"), config)),
      ring_(static_cast<std::size_t>(config.queue_capacity)) {
  const RosDefaultQos qos(config_);
  auto make_writer = [&](const dds_topic_descriptor_t* desc, const std::string& name, const dds_qos_t* q) {
    const dds_entity_t topic = participant_.create_topic(desc, name);
    return dds_check(dds_create_writer(participant_.get(), topic, q, nullptr), "DDS writer " + name);
  };
  if (config_.publish_pose) {
    writers_[0] = make_writer(&geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc, config_.pose_topic(), qos.get());
  }
  if (config_.publish_odom)
    writers_[1] = make_writer(&nav_msgs_msg_dds__Odometry__desc, config_.odom_topic(), qos.get());
  if (config_.publish_status)
    writers_[2] = make_writer(&agvslam_msgs_msg_dds__Status__desc, config_.status_topic(), qos.get());
  if (config_.publish_tf) {
    // tf2_ros::DynamicBroadcasterQoS: reliable, keep last 100, volatile.
    const RosDefaultQos tf_qos(config_, 100, false);
    writers_[3] = make_writer(&tf2_msgs_msg_dds__TFMessage__desc, DdsConfig::tf_topic(), tf_qos.get());
  }
  if (config_.publish_tf_static) {
    // tf2_ros::StaticBroadcasterQoS: reliable, keep last 1, transient local (the writer keeps the latest message
    // for readers that join later).
    const RosDefaultQos static_qos(config_, 1, true);
    writers_[4] = make_writer(&tf2_msgs_msg_dds__TFMessage__desc, DdsConfig::tf_static_topic(), static_qos.get());
  }
  if (start_thread) thread_ = std::thread([this] { run(); });
}

DdsPosePublisher::~DdsPosePublisher() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

bool DdsPosePublisher::publish(const PoseSample& sample) {
  submitted_.fetch_add(1, std::memory_order_relaxed);
  bool dropped = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (count_ == ring_.size()) {  // drop the oldest waiting sample: the newest pose matters most
      head_ = (head_ + 1) % ring_.size();
      --count_;
      dropped = true;
    }
    ring_[(head_ + count_) % ring_.size()] = sample;
    ++count_;
  }
  if (dropped) dropped_.fetch_add(1, std::memory_order_relaxed);
  wake_.notify_one();
  return !dropped;
}

bool DdsPosePublisher::write_now(const PoseSample& sample) {
  bool ok = true;
  if (writers_[0] > 0) {
    PoseMsg m{};
    fill_pose_msg(sample, frames_, m);
    ok = dds_write(writers_[0], &m) >= 0 && ok;
  }
  if (writers_[1] > 0) {
    OdomMsg m{};
    fill_odom_msg(sample, frames_, m);
    ok = dds_write(writers_[1], &m) >= 0 && ok;
  }
  if (writers_[2] > 0) {
    StatusMsg m{};
    fill_status_msg(sample, frames_, m);
    ok = dds_write(writers_[2], &m) >= 0 && ok;
  }
  if (writers_[3] > 0) {
    // map -> odom -> base_link when an odometry pose is current, so odom -> base_link stays smooth while the map
    // correction jumps; else map -> base_link.
    const bool via_odom = sample.odom_valid && frames_.odom != frames_.map;
    TransformMsg transforms[2]{};
    if (via_odom) {
      fill_transform_msg(sample.t_ns, sample.T_map_base * sample.T_odom_base.inverse(), frames_.map, frames_.odom,
                         transforms[0]);
      fill_transform_msg(sample.t_ns, sample.T_odom_base, frames_.odom, frames_.base, transforms[1]);
    } else {
      fill_transform_msg(sample.t_ns, sample.T_map_base, frames_.map, frames_.base, transforms[0]);
    }
    ok = write_transforms(writers_[3], transforms, via_odom ? 2 : 1) && ok;
  }
  if (ok) {
    published_.fetch_add(1, std::memory_order_relaxed);
  } else {
    write_errors_.fetch_add(1, std::memory_order_relaxed);
  }
  return ok;
}

bool DdsPosePublisher::write_static_transform(int64_t t_ns, const SE3d& T_parent_child, const std::string& parent,
                                              const std::string& child) {
  if (writers_[4] <= 0) return false;
  TransformMsg transform{};
  fill_transform_msg(t_ns, T_parent_child, parent, child, transform);
  return write_transforms(writers_[4], &transform, 1);
}

void DdsPosePublisher::run() {
  PoseSample sample;
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stop_ || count_ > 0; });
    if (count_ == 0 && stop_) break;
    sample = ring_[head_];
    head_ = (head_ + 1) % ring_.size();
    --count_;
    writing_ = true;
    lock.unlock();
    write_now(sample);
    lock.lock();
    writing_ = false;
    if (count_ == 0) idle_.notify_all();
  }
  idle_.notify_all();
}

bool DdsPosePublisher::flush(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!idle_.wait_until(lock, deadline, [this] { return (count_ == 0 && !writing_) || !thread_.joinable(); })) {
      return false;
    }
  }
  for (dds_entity_t w : writers_) {
    if (w <= 0) continue;
    const auto left = std::chrono::duration_cast<std::chrono::nanoseconds>(deadline - std::chrono::steady_clock::now());
    if (dds_wait_for_acks(w, std::max<int64_t>(0, left.count())) < 0) return false;
  }
  return true;
}

int DdsPosePublisher::matched_subscribers(Topic topic) const {
  const dds_entity_t w = writers_[static_cast<std::size_t>(topic)];
  if (w <= 0) return 0;
  dds_publication_matched_status_t st{};
  if (dds_get_publication_matched_status(w, &st) < 0) return 0;
  return static_cast<int>(st.current_count);
}

bool DdsPosePublisher::wait_for_subscribers(int count, std::chrono::milliseconds timeout) const {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    bool all = true;
    for (Topic t : {Topic::kPose, Topic::kOdom, Topic::kStatus}) {
      if (writers_[static_cast<std::size_t>(t)] > 0 && matched_subscribers(t) < count) all = false;
    }
    if (all) return true;
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

DdsPublisherStats DdsPosePublisher::stats() const {
  DdsPublisherStats s;
  s.submitted = submitted_.load();
  s.published = published_.load();
  s.dropped_queue_full = dropped_.load();
  s.write_errors = write_errors_.load();
  return s;
}

}  // namespace agvslam::drivers::dds
