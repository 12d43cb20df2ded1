// Wheel odometry CSV "t_s, speed_mps, yaw_rate_radps" (agvslam-run --odometry).
#include "agvslam/io/odometry_io.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string path = agvslam::fuzz::as_file(data, size, "odometry.csv");
  agvslam::fuzz::expect_input_error_or_success([&] {
    if (agvslam::io::looks_like_odometry_csv(path)) agvslam::io::read_odometry_csv(path);
  });
  agvslam::fuzz::expect_input_error_or_success([&] { agvslam::io::read_odometry_csv(path); });
  return 0;
}
