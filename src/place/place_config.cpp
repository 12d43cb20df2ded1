#include "agvslam/place/place_config.h"

#include <filesystem>

#include "agvslam/core/param_table.h"

namespace agvslam::place {
namespace {

const params::Table<PlaceConfig>& place_params() {
  static const params::Table<PlaceConfig> table(
      "vocabulary", {
                        {"file", &PlaceConfig::vocabulary_file, params::Text::non_empty(),
                         "the vocabulary file, relative to the params file's folder"},
                        {"direct_index_level", &PlaceConfig::direct_index_level, params::Range::closed(1, 8), "",
                         "a depth of the vocabulary tree, which has at most 8 levels"},
                    });
  return table;
}

}  // namespace

void PlaceConfig::validate(const std::string& source) const { place_params().validate(source, *this); }

std::string PlaceConfig::describe() const { return place_params().describe(*this); }

PlaceConfig load_place_config(const std::string& path) {
  PlaceConfig c;
  params::read_sections(params::File(path), {place_params().reader(c)});
  const std::filesystem::path file(c.vocabulary_file);
  if (!file.empty() && file.is_relative())
    c.vocabulary_file = (std::filesystem::path(path).parent_path() / file).lexically_normal().string();
  c.validate(path);
  return c;
}

}  // namespace agvslam::place
