// The map file's keypoint checks (map_io.h): a keypoint must lie inside the camera's image.

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstring>
#include <limits>
#include <string>

#include "agvslam/core/error.h"
#include "agvslam/slam/key_frame.h"
#include "agvslam/slam/map_io.h"
#include "synthetic_world.h"

namespace agvslam::slam {
namespace {

// A map of one keyframe with two keypoints, encoded.
std::string one_keyframe_map(const FrameGeometryPtr& geometry, const MapFileContext& context) {
  Map map;
  const std::vector<cv::KeyPoint> kps = {cv::KeyPoint(100.f, 50.f, 31.f, 0.f, 1.f, 0),
                                         cv::KeyPoint(700.f, 400.f, 31.f, 0.f, 1.f, 1)};
  cv::Mat descs(2, 32, CV_8UC1, cv::Scalar(0x5A));
  Frame frame;
  frame.assign(0, 0, geometry, kps, descs, {-1.f, -1.f}, {-1.f, -1.f});
  frame.set_pose(SE3d::Identity());
  map.add_keyframe(std::make_shared<KeyFrame>(map.new_keyframe_id(), frame));
  return encode_map(map, context);
}

// Offset of keypoint 0's x: header, camera (5 f64, 3 i32, f64), counters (3 u64), then the keyframe's id, frame
// id, t_ns, 12 f64 of T_c_w and the u32 keypoint count (map_io.h's layout).
constexpr std::size_t kFirstKeypointX = kMapHeaderBytes + 5 * 8 + 3 * 4 + 8 + 3 * 8 + 3 * 8 + 12 * 8 + 4;

// The checksums of bytes changed on purpose, so that the decoder reaches the field under test.
void refresh_crcs(std::string& bytes) {
  auto crc = [](const char* p, std::size_t n) {
    return static_cast<uint32_t>(crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(p), static_cast<uInt>(n)));
  };
  const uint32_t payload = crc(bytes.data() + kMapHeaderBytes, bytes.size() - kMapHeaderBytes);
  std::memcpy(bytes.data() + 24, &payload, 4);
  const uint32_t header = crc(bytes.data(), 60);
  std::memcpy(bytes.data() + 60, &header, 4);
}

// Found by tests/fuzz (map): a keypoint at x = -1.3e33 overflowed the feature grid's cell index.
TEST(MapFile, KeypointOutsideTheImageIsRefusedWithItsKeyframe) {
  const FrameGeometryPtr geometry = test::test_geometry();
  const MapFileContext context = MapFileContext::from(*geometry, 0, 0);
  const std::string good = one_keyframe_map(geometry, context);
  {
    Map loaded;
    decode_map(good, "good.map", context, geometry, loaded);
    EXPECT_EQ(loaded.keyframes().size(), 1u);
  }
  float x = 0;
  std::memcpy(&x, good.data() + kFirstKeypointX, 4);
  ASSERT_EQ(x, 100.f);  // the layout above
  for (const float bad : {-1.3e33f, 753.f, -0.5f, std::numeric_limits<float>::quiet_NaN()}) {
    std::string bytes = good;
    std::memcpy(bytes.data() + kFirstKeypointX, &bad, 4);
    refresh_crcs(bytes);
    Map loaded;
    try {
      decode_map(bytes, "bad.map", context, geometry, loaded);
      ADD_FAILURE() << "accepted x = " << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(e.source(), "bad.map");
      EXPECT_EQ(e.where(), "keyframe 0 keypoint 0");
      EXPECT_NE(e.expected().find("inside the 752x480 image"), std::string::npos) << e.expected();
    }
    EXPECT_TRUE(loaded.keyframes().empty());
  }
}

}  // namespace
}  // namespace agvslam::slam
