// params/place.yaml: the shipped file, relative vocabulary paths, and errors naming the file and the field.
#include "agvslam/place/place_config.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "agvslam/core/error.h"
#include "common/test_data.h"

namespace agvslam::place {
namespace {
namespace fs = std::filesystem;

TEST(PlaceConfig, ShippedFileNamesTheShippedVocabulary) {
  const std::string params = std::string(AGVSLAM_SOURCE_DIR) + "/params/place.yaml";
  const PlaceConfig c = load_place_config(params);
  EXPECT_EQ(fs::weakly_canonical(c.vocabulary_file),
            fs::weakly_canonical(std::string(AGVSLAM_SOURCE_DIR) + "/params/vocabulary/agvslam_orb_k10l5.bin"));
  EXPECT_TRUE(fs::exists(c.vocabulary_file));
  EXPECT_EQ(c.direct_index_level, PlaceConfig{}.direct_index_level);
  EXPECT_NE(c.describe().find("direct_index_level=2"), std::string::npos);
}

TEST(PlaceConfig, RelativeAbsoluteAndBadValues) {
  const std::string dir = agvslam::test::make_temp_dir("agvslam-place-config");
  const std::string path = (fs::path(dir) / "place.yaml").string();
  std::ofstream(path) << "vocabulary:\n  file: voc/v.bin\n  direct_index_level: 3\n";
  PlaceConfig c = load_place_config(path);
  EXPECT_EQ(c.vocabulary_file, (fs::path(dir) / "voc/v.bin").string());
  EXPECT_EQ(c.direct_index_level, 3);
  std::ofstream(path, std::ios::trunc) << "vocabulary:\n  file: /abs/v.bin\n";
  EXPECT_EQ(load_place_config(path).vocabulary_file, "/abs/v.bin");
  for (const auto& [text, field] : std::vector<std::pair<std::string, std::string>>{
           {"vocabulary:\n  direct_index_level: 0\n", "vocabulary.direct_index_level"},
           {"vocabulary:\n  direct_index_levle: 2\n", "vocabulary.direct_index_levle"},
           {"vocabulary:\n  direct_index_level: two\n", "vocabulary.direct_index_level"}}) {
    std::ofstream(path, std::ios::trunc) << text;
    try {
      load_place_config(path);
      ADD_FAILURE() << text;
    } catch (const InputError& e) {
      EXPECT_EQ(e.source(), path);
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace agvslam::place
