// EuRoC ASL CSV files as EurocDataset reads them: the bytes are mav0/cam0/data.csv and mav0/cam1/data.csv (the
// image index, paired by time stamp) and mav0/state_groundtruth_estimate0/data.csv (body poses), in a folder
// whose sensor.yaml files are V1_01's cameras at a quarter of the resolution (cheap rectification maps) and whose
// data/ folders hold the first images of V1_01 by name (empty files: the index only checks they exist).
#include <filesystem>
#include <string>

#include "agvslam/io/dataset.h"
#include "fuzz_common.h"

namespace {

namespace fs = std::filesystem;

std::string sensor_yaml(const char* T_BS, const char* intrinsics, const char* distortion) {
  return std::string("%YAML:1.0\nsensor_type: camera\nT_BS:\n  cols: 4\n  rows: 4\n  data: [") + T_BS +
         ", 0.0, 0.0, 0.0, 1.0]\nrate_hz: 20\nresolution: [188, 120]\ncamera_model: pinhole\nintrinsics: [" +
         intrinsics + "]\ndistortion_model: radial-tangential\ndistortion_coefficients: [" + distortion + "]\n";
}

void write_text(const fs::path& path, const std::string& text) {
  agvslam::fuzz::write_bytes(path, reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

const fs::path& dataset_root() {
  static const fs::path root = [] {
    const fs::path r = agvslam::fuzz::scratch_dir() / "euroc";
    const char* kImages[] = {"1403715273262142976", "1403715273312143104", "1403715273362142976",
                             "1403715273412143104", "1403715273462142976", "1403715273512143104"};
    for (const char* cam : {"cam0", "cam1"}) {
      fs::create_directories(r / "mav0" / cam / "data");
      for (const char* t : kImages) write_text(r / "mav0" / cam / "data" / (std::string(t) + ".png"), "");
    }
    fs::create_directories(r / "mav0" / "state_groundtruth_estimate0");
    write_text(
        r / "mav0" / "cam0" / "sensor.yaml",
        sensor_yaml("0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975, 0.999557249008, "
                    "0.0149672133247, 0.025715529948, -0.064676986768, -0.0257744366974, 0.00375618835797, "
                    "0.999660727178, 0.00981073058949",
                    "114.6635, 114.324, 91.80375, 62.09375", "-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05"));
    write_text(
        r / "mav0" / "cam1" / "sensor.yaml",
        sensor_yaml("0.0125552670891, -0.999755099723, 0.0182237714554, -0.0198435579556, 0.999598781151, "
                    "0.0130119051815, 0.0251588363115, 0.0453689425024, -0.0253898008918, 0.0179005838253, "
                    "0.999517347078, 0.00786212447038",
                    "114.39675, 114.0335, 94.99975, 63.8095", "-0.28368365, 0.07451284, -0.00010473, -3.55590700e-05"));
    return r;
  }();
  return root;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const fs::path& root = dataset_root();
  for (const char* csv : {"cam0/data.csv", "cam1/data.csv", "state_groundtruth_estimate0/data.csv"}) {
    agvslam::fuzz::write_bytes(root / "mav0" / csv, data, size);
  }
  agvslam::fuzz::expect_input_error_or_success([&] {
    const agvslam::io::EurocDataset dataset(root.string());
    for (std::size_t i = 0; i < dataset.size(); ++i) dataset.timestamp_ns(i);
    dataset.ground_truth();
  });
  return 0;
}
