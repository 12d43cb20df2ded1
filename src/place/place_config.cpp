#include "agvslam/place/place_config.h"

#include <filesystem>

#include "agvslam/core/error.h"
#include "agvslam/stereo/params_reader.h"

namespace agvslam::place {

void PlaceConfig::validate(const std::string& source) const {
  if (vocabulary_file.empty()) throw InputError(source, "vocabulary.file", "expected the path of a vocabulary file");
  if (direct_index_level < 1 || direct_index_level > 8)
    throw InputError(source, "vocabulary.direct_index_level", "expected a tree depth in 1..8 (at most L)");
}

std::string PlaceConfig::describe() const {
  return "place: vocabulary=" + vocabulary_file + " direct_index_level=" + std::to_string(direct_index_level);
}

PlaceConfig load_place_config(const std::string& path) {
  const stereo::ParamsReader in(path);
  in.check_sections({"vocabulary"});
  in.check_keys("vocabulary", {"file", "direct_index_level"});
  PlaceConfig c;
  in.read("vocabulary", "file", c.vocabulary_file, "a file path (relative to this file's folder)");
  in.read("vocabulary", "direct_index_level", c.direct_index_level, "an integer tree depth (1..L)");
  const std::filesystem::path file(c.vocabulary_file);
  if (!file.empty() && file.is_relative())
    c.vocabulary_file = (std::filesystem::path(path).parent_path() / file).lexically_normal().string();
  c.validate(path);
  return c;
}

}  // namespace agvslam::place
