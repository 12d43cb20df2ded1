// DDS samples as a reader on the daemon's topics receives them (agvslam-echo, DdsPoseSubscriber): the serialized
// payload checked and byte-swapped by Cyclone's dds_stream_normalize_data, as its receive path does before it
// accepts a sample, then read into the idlc-generated struct and turned into the JSON agvslam-echo prints.
// Input: 1 byte choosing the topic (pose, odom, status), then the payload as on the wire: the 2-byte
// encapsulation identifier (CDR_BE 0x0000 or CDR_LE 0x0001, what ROS 2's rmw_cyclonedds writes), 2 option bytes,
// the data. XCDR2 identifiers (0x0006..0x000b) are left out: with them Debian's Cyclone 0.10.2 reads past the end
// of data its own normalize accepted (tests/fuzz/known_issues/dds_samples, README.md there).
#include <dds/dds.h>
#include <dds/ddsi/ddsi_cdrstream.h>

#include <cstdlib>
#include <nlohmann/json.hpp>
#include <vector>

#include "agvslam/drivers/dds/ros_messages.h"
#include "fuzz_common.h"

namespace {

template <class Msg>
void read_sample(const dds_topic_descriptor_t& desc, const std::vector<char>& payload, uint32_t xcdr_version,
                 bool bswap) {
  std::vector<char> bytes = payload;  // normalised in place
  uint32_t offset = 0;
  if (dds_stream_normalize_data(bytes.data(), &offset, static_cast<uint32_t>(bytes.size()), bswap, xcdr_version,
                                desc.m_ops) == nullptr) {
    return;  // refused: Cyclone drops the sample
  }
  dds_istream_t in{reinterpret_cast<const unsigned char*>(bytes.data()), static_cast<uint32_t>(bytes.size()), 0,
                   xcdr_version};
  void* sample = std::calloc(1, desc.m_size);
  dds_stream_read(&in, static_cast<char*>(sample), desc.m_ops);
  agvslam::drivers::dds::to_json(*static_cast<const Msg*>(sample)).dump();
  dds_sample_free(sample, &desc, DDS_FREE_ALL);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  using namespace agvslam::drivers::dds;
  if (size < 6) return 0;  // selector, encapsulation header and at least one byte of data
  const uint16_t identifier = static_cast<uint16_t>((data[1] << 8) | data[2]);
  if (identifier > 0x0001) return 0;  // not XCDR1
  const uint32_t xcdr_version = 1;
  const bool little_endian = (identifier & 1) != 0;
  const bool bswap = little_endian != (__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__);
  const std::vector<char> payload(reinterpret_cast<const char*>(data) + 5, reinterpret_cast<const char*>(data) + size);
  switch (data[0] % 3) {
    case 0:
      read_sample<PoseMsg>(geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc, payload, xcdr_version, bswap);
      break;
    case 1:
      read_sample<OdomMsg>(nav_msgs_msg_dds__Odometry__desc, payload, xcdr_version, bswap);
      break;
    default:
      read_sample<StatusMsg>(agvslam_msgs_msg_dds__Status__desc, payload, xcdr_version, bswap);
      break;
  }
  return 0;
}
