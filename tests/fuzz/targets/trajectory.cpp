// Trajectory files as agvslam-eval reads them: the format guessed from the first data line (TUM, KITTI poses,
// EuRoC CSV), then read.
#include "agvslam/io/trajectory_io.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string path = agvslam::fuzz::as_file(data, size, "trajectory.txt");
  agvslam::fuzz::expect_input_error_or_success([&] {
    const agvslam::io::TrajectoryFormat format = agvslam::io::guess_trajectory_format(path);
    agvslam::io::read_trajectory(path, format);
  });
  return 0;
}
