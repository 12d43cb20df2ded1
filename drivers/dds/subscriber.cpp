#include "agvslam/drivers/dds/subscriber.h"

#include <ctime>

namespace agvslam::drivers::dds {
namespace {

constexpr int kTakeBatch = 32;

template <typename Msg, typename Handler>
int take_all(dds_entity_t reader, const Handler& handler) {
  int delivered = 0;
  for (;;) {
    void* samples[kTakeBatch] = {};
    dds_sample_info_t infos[kTakeBatch];
    const dds_return_t n = dds_take(reader, samples, infos, kTakeBatch, kTakeBatch);  // loans the samples
    if (n <= 0) break;
    const int64_t recv_t_ns = realtime_now_ns();
    for (int i = 0; i < n; ++i) {
      if (!infos[i].valid_data) continue;
      handler(*static_cast<const Msg*>(samples[i]), recv_t_ns);
      ++delivered;
    }
    dds_return_loan(reader, samples, n);
    if (n < kTakeBatch) break;
  }
  return delivered;
}

}  // namespace

int64_t realtime_now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

DdsPoseSubscriber::DdsPoseSubscriber(const DdsConfig& config, SubscriberHandlers handlers)
    : participant_(config), handlers_(std::move(handlers)) {
  const RosDefaultQos qos(config);
  waitset_ = DdsEntity(dds_check(dds_create_waitset(participant_.get()), "DDS waitset"));
  auto make_reader = [&](const dds_topic_descriptor_t* desc, const std::string& name,
                         const dds_qos_t* reader_qos = nullptr) {
    const dds_entity_t topic = participant_.create_topic(desc, name);
    const dds_entity_t r =
        dds_check(dds_create_reader(participant_.get(), topic, reader_qos != nullptr ? reader_qos : qos.get(), nullptr),
                  "DDS reader " + name);
    dds_check(dds_set_status_mask(r, DDS_DATA_AVAILABLE_STATUS), "DDS reader " + name + ": status mask");
    dds_check(dds_waitset_attach(waitset_.get(), r, r), "DDS reader " + name + ": attach to waitset");
    return r;
  };
  if (handlers_.on_pose) {
    readers_[0] = make_reader(&geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc, config.pose_topic());
  }
  if (handlers_.on_odom) readers_[1] = make_reader(&nav_msgs_msg_dds__Odometry__desc, config.odom_topic());
  if (handlers_.on_status) readers_[2] = make_reader(&agvslam_msgs_msg_dds__Status__desc, config.status_topic());
  if (handlers_.on_tf) {
    const RosDefaultQos tf_qos(config, 100, false);
    readers_[3] = make_reader(&tf2_msgs_msg_dds__TFMessage__desc, DdsConfig::tf_topic(), tf_qos.get());
  }
  if (handlers_.on_tf_static) {
    const RosDefaultQos static_qos(config, 1, true);
    readers_[4] = make_reader(&tf2_msgs_msg_dds__TFMessage__desc, DdsConfig::tf_static_topic(), static_qos.get());
  }
}

int DdsPoseSubscriber::poll(std::chrono::milliseconds timeout) {
  dds_attach_t triggered[5];
  const dds_return_t n = dds_waitset_wait(waitset_.get(), triggered, 5, DDS_MSECS(timeout.count()));
  if (n < 0) throw DdsError(std::string("DDS waitset wait: ") + dds_strretcode(n));
  int delivered = 0;
  if (readers_[0] > 0) delivered += take_all<PoseMsg>(readers_[0], handlers_.on_pose);
  if (readers_[1] > 0) delivered += take_all<OdomMsg>(readers_[1], handlers_.on_odom);
  if (readers_[2] > 0) delivered += take_all<StatusMsg>(readers_[2], handlers_.on_status);
  if (readers_[3] > 0) delivered += take_all<TfMsg>(readers_[3], handlers_.on_tf);
  if (readers_[4] > 0) delivered += take_all<TfMsg>(readers_[4], handlers_.on_tf_static);
  return delivered;
}

int DdsPoseSubscriber::matched_publishers(Topic topic) const {
  const dds_entity_t r = readers_[static_cast<std::size_t>(topic)];
  if (r <= 0) return 0;
  dds_subscription_matched_status_t st{};
  if (dds_get_subscription_matched_status(r, &st) < 0) return 0;
  return static_cast<int>(st.current_count);
}

}  // namespace agvslam::drivers::dds
