// The saved map file (agvslam-run --save-map, the daemon's map.file), decoded by decode_map as the system's
// load does. Two things make the mutated bytes reach the payload parser: the camera the file must agree with is
// taken from the file itself (a camera mismatch is one comparison, refused at once), and both CRC-32s are
// recomputed over the mutated bytes (map_io.h's layout).
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <string>

#include "agvslam/slam/map_io.h"
#include "fuzz_common.h"

namespace {

using agvslam::slam::kMapHeaderBytes;

template <class T>
T read_at(const std::string& bytes, std::size_t offset) {
  T value{};
  if (offset + sizeof(T) <= bytes.size()) std::memcpy(&value, bytes.data() + offset, sizeof(T));
  return value;
}

uint32_t crc32_of(const char* data, std::size_t size) {
  uLong crc = crc32(0L, Z_NULL, 0);
  // zlib's length is a uInt: a file of 4 GiB or more would need several calls; fuzz inputs are far smaller.
  crc = crc32(crc, reinterpret_cast<const Bytef*>(data), static_cast<uInt>(size));
  return static_cast<uint32_t>(crc);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  using namespace agvslam::slam;
  std::string bytes(reinterpret_cast<const char*>(data), size);
  if (bytes.size() >= kMapHeaderBytes) {
    const uint32_t payload_crc = crc32_of(bytes.data() + kMapHeaderBytes, bytes.size() - kMapHeaderBytes);
    std::memcpy(bytes.data() + 24, &payload_crc, 4);
    const uint32_t header_crc = crc32_of(bytes.data(), 60);
    std::memcpy(bytes.data() + 60, &header_crc, 4);
  }

  // The camera the payload starts with: f64 fx fy cx cy baseline_m, i32 width height levels, f64 scale factor.
  const std::size_t p = kMapHeaderBytes;
  agvslam::PinholeCamera camera;
  camera.fx = read_at<double>(bytes, p);
  camera.fy = read_at<double>(bytes, p + 8);
  camera.cx = read_at<double>(bytes, p + 16);
  camera.cy = read_at<double>(bytes, p + 24);
  double baseline_m = read_at<double>(bytes, p + 32);
  camera.width = read_at<int32_t>(bytes, p + 40);
  camera.height = read_at<int32_t>(bytes, p + 44);
  int n_levels = read_at<int32_t>(bytes, p + 48);
  double scale_factor = read_at<double>(bytes, p + 52);
  const bool sane = camera.valid() && camera.width <= 8192 && camera.height <= 8192 && std::isfinite(camera.fx) &&
                    std::isfinite(camera.fy) && std::isfinite(camera.cx) && std::isfinite(camera.cy) &&
                    std::isfinite(baseline_m) && baseline_m > 0 && n_levels >= 1 && n_levels <= 16 &&
                    std::isfinite(scale_factor) && scale_factor > 1.0 && scale_factor < 4.0;
  if (!sane) {  // the KITTI excerpts' camera: the file is refused at the camera check
    camera = agvslam::PinholeCamera{718.856, 718.856, 607.1928, 185.2157, 1241, 376};
    baseline_m = 0.5372;
    n_levels = 8;
    scale_factor = 1.2;
  }
  const FrameGeometryPtr geometry =
      std::make_shared<const FrameGeometry>(FrameGeometry::make(camera, baseline_m, 40.0, n_levels, scale_factor));
  const MapFileContext context =
      MapFileContext::from(*geometry, read_at<uint64_t>(bytes, 32), static_cast<int>(read_at<uint32_t>(bytes, 56)));

  agvslam::fuzz::expect_input_error_or_success([&] {
    Map map;
    decode_map(bytes, "fuzz.map", context, geometry, map);
  });
  agvslam::fuzz::expect_input_error_or_success([&] { check_map_file(bytes, "fuzz.map"); });
  return 0;
}
