// A rosbag2 recording's metadata.yaml as RosbagDataset reads it (the folder holds no .db3, so a well-formed one
// ends at the first file lookup with an InputError), and the topic choice of a `BAG?left=..&right=..` path.
#include <filesystem>

#include "agvslam/io/rosbag_dataset.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::filesystem::path bag = agvslam::fuzz::scratch_dir() / "bag";
  std::filesystem::create_directories(bag);
  agvslam::fuzz::write_bytes(bag / "metadata.yaml", data, size);
  agvslam::fuzz::expect_input_error_or_success([&] { agvslam::io::RosbagDataset dataset(bag.string()); });
  const std::string query(reinterpret_cast<const char*>(data), size);
  agvslam::fuzz::expect_input_error_or_success([&] { agvslam::io::parse_rosbag_topics(query, "fuzz?query"); });
  return 0;
}
