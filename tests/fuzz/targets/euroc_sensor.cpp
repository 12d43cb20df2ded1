// One EuRoC mav0/camN/sensor.yaml (intrinsics, distortion, resolution, T_BS).
#include "agvslam/io/calibration_io.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string path = agvslam::fuzz::as_file(data, size, "sensor.yaml");
  agvslam::fuzz::expect_input_error_or_success([&] { agvslam::io::load_euroc_sensor(path); });
  return 0;
}
