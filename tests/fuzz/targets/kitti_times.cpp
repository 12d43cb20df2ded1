// KITTI times.txt (seconds, one a line), read with every KITTI-layout dataset.
#include "agvslam/io/trajectory_io.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string path = agvslam::fuzz::as_file(data, size, "times.txt");
  agvslam::fuzz::expect_input_error_or_success([&] { agvslam::io::read_kitti_times(path); });
  return 0;
}
