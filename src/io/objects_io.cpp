#include "agvslam/io/objects_io.h"

#include <string_view>

#include "agvslam/core/error.h"
#include "text_util.h"

namespace agvslam::io {

std::map<int, std::vector<SceneObject>> read_objects_file(const std::string& path) {
  detail::LineReader reader(path, detail::read_text_file(path));
  std::map<int, std::vector<SceneObject>> objects;
  std::string_view line;
  while (reader.next(line)) {
    if (detail::is_blank_or_comment(line)) continue;
    const auto tokens = detail::split_tokens(line, false);
    if (tokens.size() != 8) {
      throw InputError(
          path, reader.where(),
          "expected 8 fields 'frame id class moving x_min y_min x_max y_max', found " + std::to_string(tokens.size()));
    }
    int64_t values[7];
    const char* names[7] = {"frame", "id", "moving", "x_min", "y_min", "x_max", "y_max"};
    const std::size_t index[7] = {0, 1, 3, 4, 5, 6, 7};
    for (int k = 0; k < 7; ++k) {
      if (!detail::parse_int64(tokens[index[k]], values[k])) {
        throw InputError(
            path, reader.where(),
            std::string("expected an integer for ") + names[k] + ", found '" + std::string(tokens[index[k]]) + "'");
      }
    }
    if (values[0] < 0) throw InputError(path, reader.where(), "expected a non-negative frame index");
    if (values[2] != 0 && values[2] != 1) throw InputError(path, reader.where(), "expected moving to be 0 or 1");
    if (values[5] < values[3] || values[6] < values[4] || values[3] < 0 || values[4] < 0) {
      throw InputError(path, reader.where(), "expected 0 <= x_min <= x_max and 0 <= y_min <= y_max");
    }
    SceneObject o;
    o.id = static_cast<int>(values[1]);
    o.object_class = std::string(tokens[2]);
    o.moving = values[2] == 1;
    o.box = cv::Rect(static_cast<int>(values[3]), static_cast<int>(values[4]),
                     static_cast<int>(values[5] - values[3] + 1), static_cast<int>(values[6] - values[4] + 1));
    objects[static_cast<int>(values[0])].push_back(o);
  }
  return objects;
}

}  // namespace agvslam::io
