#pragma once
// Helpers for the tests of params/*.yaml loaders: a YAML text in a file of its own, and the check that loading it
// fails with an InputError that names that file and the field.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

#include "agvslam/core/error.h"
#include "common/test_data.h"

namespace agvslam::test {

// `text` written to <a new temporary folder>/<file_name>; the folder is removed with the object.
class TempYaml {
 public:
  explicit TempYaml(const std::string& text, const std::string& file_name = "params.yaml") {
    dir_ = make_temp_dir("agvslam-config");
    path_ = (std::filesystem::path(dir_) / file_name).string();
    std::ofstream(path_) << text;
  }
  ~TempYaml() {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  TempYaml(const TempYaml&) = delete;
  TempYaml& operator=(const TempYaml&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string dir_, path_;
};

// load(path) on `text` must throw an InputError whose source is the file, whose field is `field`, and whose message
// names the file and says what was expected (exactly `expected` when that is not empty).
template <class Load>
void expect_input_error(Load&& load, const std::string& text, const std::string& field,
                        const std::string& expected = "") {
  TempYaml f(text);
  try {
    load(f.path());
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const InputError& e) {
    EXPECT_EQ(e.source(), f.path()) << e.what();
    EXPECT_EQ(e.where(), field) << e.what();
    EXPECT_FALSE(e.expected().empty()) << e.what();
    EXPECT_NE(std::string(e.what()).find(f.path()), std::string::npos) << e.what();
    if (!expected.empty()) {
      EXPECT_EQ(e.expected(), expected);
    }
  }
}

}  // namespace agvslam::test
