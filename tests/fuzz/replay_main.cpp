// agvslam_fuzz_replay TARGET PATH...: feeds every file (folders: every file in them, sorted) to one fuzz target's
// function, as the libFuzzer build does with a corpus, in the normal (gcc, release) build. A crash or an
// exception other than InputError fails the run; prints the number of inputs.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#define AGVSLAM_FUZZ_TARGET(name) extern "C" int fuzz_##name(const uint8_t* data, std::size_t size);
AGVSLAM_FUZZ_TARGET(calibration)
AGVSLAM_FUZZ_TARGET(euroc_sensor)
AGVSLAM_FUZZ_TARGET(euroc_csv)
AGVSLAM_FUZZ_TARGET(kitti_times)
AGVSLAM_FUZZ_TARGET(trajectory)
AGVSLAM_FUZZ_TARGET(odometry_csv)
AGVSLAM_FUZZ_TARGET(objects)
AGVSLAM_FUZZ_TARGET(params)
AGVSLAM_FUZZ_TARGET(map)
AGVSLAM_FUZZ_TARGET(vocabulary)
AGVSLAM_FUZZ_TARGET(candump)
AGVSLAM_FUZZ_TARGET(dbc)
AGVSLAM_FUZZ_TARGET(can_frames)
AGVSLAM_FUZZ_TARGET(rosbag_cdr)
AGVSLAM_FUZZ_TARGET(rosbag_metadata)
AGVSLAM_FUZZ_TARGET(dds_samples)
#undef AGVSLAM_FUZZ_TARGET

int main(int argc, char** argv) {
  using Fn = int (*)(const uint8_t*, std::size_t);
  const std::map<std::string, Fn> targets = {
      {"calibration", fuzz_calibration},
      {"euroc_sensor", fuzz_euroc_sensor},
      {"euroc_csv", fuzz_euroc_csv},
      {"kitti_times", fuzz_kitti_times},
      {"trajectory", fuzz_trajectory},
      {"odometry_csv", fuzz_odometry_csv},
      {"objects", fuzz_objects},
      {"params", fuzz_params},
      {"map", fuzz_map},
      {"vocabulary", fuzz_vocabulary},
      {"candump", fuzz_candump},
      {"dbc", fuzz_dbc},
      {"can_frames", fuzz_can_frames},
      {"rosbag_cdr", fuzz_rosbag_cdr},
      {"rosbag_metadata", fuzz_rosbag_metadata},
      {"dds_samples", fuzz_dds_samples},
  };
  if (argc < 2 || targets.count(argv[1]) == 0) {
    std::fprintf(stderr, "usage: agvslam_fuzz_replay TARGET PATH...   (TARGET one of:");
    for (const auto& t : targets) std::fprintf(stderr, " %s", t.first.c_str());
    std::fprintf(stderr, ")\n");
    return 2;
  }
  const Fn fn = targets.at(argv[1]);
  std::vector<std::filesystem::path> files;
  for (int i = 2; i < argc; ++i) {
    const std::filesystem::path p(argv[i]);
    if (std::filesystem::is_directory(p)) {
      for (const auto& e : std::filesystem::directory_iterator(p)) {
        if (e.is_regular_file()) files.push_back(e.path());
      }
    } else if (std::filesystem::is_regular_file(p)) {
      files.push_back(p);
    } else if (std::filesystem::exists(p)) {
      std::fprintf(stderr, "%s: expected a file or a folder of inputs\n", argv[i]);
      return 2;
    }  // an absent folder (a target without kept crash inputs yet) holds no inputs
  }
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::fprintf(stderr, "%s\n", f.c_str());
    fn(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
  }
  std::printf("%s: %zu inputs replayed\n", argv[1], files.size());
  return files.empty() ? 1 : 0;
}
