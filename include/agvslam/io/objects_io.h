#pragma once
// objects.txt of a simulated sequence (written by agvslam-sim): one line per visible actor and frame,
//   frame id class moving x_min y_min x_max y_max
// class is person|forklift|agv, moving is 1 when the actor moves at that frame, the box (inclusive, pixels)
// bounds its visible pixels in image_0. Lines starting with '#' are comments.

#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace agvslam::io {

struct SceneObject {
  int id = 0;
  std::string object_class;
  bool moving = false;
  cv::Rect box;  // visible pixels in the left image (exclusive width/height: x_max - x_min + 1)
};

// Objects per frame index (frames without objects are absent). Throws InputError naming the file, the line and
// what was expected (8 fields, integers, moving 0|1, x_min <= x_max, y_min <= y_max, non-negative frame).
std::map<int, std::vector<SceneObject>> read_objects_file(const std::string& path);

}  // namespace agvslam::io
