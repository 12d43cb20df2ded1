// objects.txt of a simulated sequence (ground truth boxes per frame).
#include "agvslam/io/objects_io.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string path = agvslam::fuzz::as_file(data, size, "objects.txt");
  agvslam::fuzz::expect_input_error_or_success([&] { agvslam::io::read_objects_file(path); });
  return 0;
}
