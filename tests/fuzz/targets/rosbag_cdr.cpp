// Messages of a rosbag2 recording (the .db3's serialized CDR blobs) as RosbagDataset decodes them: the first byte
// chooses the message type (sensor_msgs Image, CompressedImage, CameraInfo, nav_msgs Odometry), the rest is the
// message with its encapsulation header.
#include "../../src/io/cdr.h"
#include "../../src/io/ros_message_decode.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  using namespace agvslam::io::detail;
  if (size < 1) return 0;
  const uint8_t kind = data[0] % 4;
  agvslam::fuzz::expect_input_error_or_success([&] {
    CdrReader in(data + 1, size - 1, "fuzz.db3", "message 1");
    switch (kind) {
      case 0:
        decode_raw_image(in, "fuzz.db3", "message 1");
        break;
      case 1:
        decode_compressed_image(in, "fuzz.db3", "message 1");
        break;
      case 2:
        decode_camera_info(in, "/camera/left/camera_info");
        break;
      default:
        decode_odometry(in);
        break;
    }
  });
  return 0;
}
