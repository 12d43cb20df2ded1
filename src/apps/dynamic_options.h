#pragma once
// agvslam-dynamic's command-line options (main() in agvslam_dynamic.cpp fills them; the report follows --json,
// --json-points, --dump-rois and --out).

#include <string>

namespace agvslam::apps::dynamic_tool {

struct Options {
  std::string dataset, out_dir, json_path, frames, params_dynamic, params_stereo, calib;
  std::string semantic = "off", params_semantic;
  int overlay_every = 10;
  int opencv_threads = 1;
  int min_object_pixels = 400;
  double min_iou = 0.5;
  bool json_points = false;
  bool dump_rois = false;
};

}  // namespace agvslam::apps::dynamic_tool
