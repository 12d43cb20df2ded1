// Calibration files as agvslam-run --calib and the datasets read them: load_calibration detects the format from
// the content (KITTI calib.txt, ORB-SLAM YAML, Kalibr camchain).
#include "agvslam/io/calibration_io.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string path = agvslam::fuzz::as_file(data, size, "calib.txt");
  agvslam::fuzz::expect_input_error_or_success([&] { agvslam::io::load_calibration(path, cv::Size(1241, 376)); });
  return 0;
}
