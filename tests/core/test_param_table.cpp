// The params file reader and the table mechanism: reading each type, unknown keys and sections, wrong types, ranges,
// rules between settings, enum names, included structs and the start-up echo.
#include "agvslam/core/param_table.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <utility>
#include <vector>

#include "agvslam/core/error.h"
#include "common/test_data.h"

namespace agvslam::params {
namespace {

enum class Shape { kRound, kSquare };

struct Inner {
  int depth_m = 2;
  std::string label = "x";
};

struct Sample {
  int count = 3;
  double gain = 0.5;
  bool enabled = true;
  std::string name = "abc";
  Shape shape = Shape::kRound;
  uint32_t id = 0x300;
  uint64_t seed = 1;
  int low = 1, high = 5;
  Inner inner;
};

const EnumNames<Shape>& shape_names() {
  static const EnumNames<Shape> names{{"round", Shape::kRound}, {"square", Shape::kSquare}, {"box", Shape::kSquare}};
  return names;
}

const Table<Inner>& inner_params() {
  static const Table<Inner> table("inner", {
                                               {"depth_m", &Inner::depth_m, Range::closed(1, 9), "m"},
                                               {"label", &Inner::label, Text::non_empty()},
                                           });
  return table;
}

const Table<Sample>& sample_params() {
  static const Table<Sample> table =
      Table<Sample>("sample",
                    {
                        {"count", &Sample::count, Range::closed(1, 10), "frames", "at least one frame"},
                        {"gain", &Sample::gain, Range::left_open(0, 1)},
                        {"enabled", &Sample::enabled},
                        {"name", &Sample::name, Text::length(1, 5)},
                        {"shape", &Sample::shape, shape_names()},
                        {"id", &Sample::id, Id{0x7FF}},
                        {"seed", &Sample::seed},
                        {"low", &Sample::low, Range::at_least(0)},
                        {"high", &Sample::high, Range::at_least(0)},
                    })
          .check(
              "high", [](const Sample& s) { return s.high > s.low; }, "more than low")
          .include(&Sample::inner, inner_params())
          .summary([](const Sample& s) { return "span " + std::to_string(s.high - s.low); });
  return table;
}

// Unsigned 32-bit settings: a seed that may take any value, and a count with a range.
struct Seeded {
  uint32_t seed = 1;
  uint32_t frames = 4;
};

const Table<Seeded>& seeded_params() {
  static const Table<Seeded> table("seeded",
                                   {
                                       {"seed", &Seeded::seed, Range::any()},
                                       {"frames", &Seeded::frames, Range::closed(1, 100), "frames", "one at least"},
                                   });
  return table;
}

class ParamsTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::make_temp_dir("agvslam-params"); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string write(const std::string& text) {
    const std::string path = dir_ + "/p" + std::to_string(++files_) + ".yaml";
    std::ofstream(path) << text;
    return path;
  }
  // Reads and validates `text`; returns the error's where() and message, or "" when it loads.
  std::pair<std::string, std::string> error_of(const std::string& text) {
    const std::string path = write(text);
    try {
      Sample s;
      const File file(path);
      read_sections(file, {sample_params().reader(s)});
      sample_params().validate(path, s);
    } catch (const InputError& e) {
      EXPECT_EQ(e.source(), path) << e.what();
      return {e.where(), e.what()};
    }
    return {"", ""};
  }
  Sample load(const std::string& text) {
    Sample s;
    const File file(write(text));
    sample_params().read(file, s);
    sample_params().validate(file.path(), s);
    return s;
  }

  std::string dir_;
  int files_ = 0;
};

TEST_F(ParamsTest, ReadsEveryTypeAndKeepsTheDefaultsOfAbsentKeys) {
  const Sample s = load(
      "sample:\n  count: 7\n  gain: 0.25\n  enabled: no\n  name: hello\n  shape: box\n  id: 0x10\n"
      "  seed: 18446744073709551615\n  depth_m: 4\n");
  EXPECT_EQ(s.count, 7);
  EXPECT_EQ(s.gain, 0.25);
  EXPECT_FALSE(s.enabled);
  EXPECT_EQ(s.name, "hello");
  EXPECT_EQ(s.shape, Shape::kSquare);  // through the alias
  EXPECT_EQ(s.id, 0x10u);
  EXPECT_EQ(s.seed, 18446744073709551615ull);
  EXPECT_EQ(s.inner.depth_m, 4);
  EXPECT_EQ(s.inner.label, "x");
  EXPECT_EQ(s.low, 1);
  EXPECT_EQ(s.high, 5);
}

TEST_F(ParamsTest, IdsAreCIntegerLiteralsAndAnEmptyOneKeepsTheDefault) {
  EXPECT_EQ(load("sample:\n  id: 768\n").id, 768u);
  EXPECT_EQ(load("sample:\n  id: 0x7FF\n").id, 0x7FFu);
  EXPECT_EQ(load("sample:\n  id: 010\n").id, 8u);
  EXPECT_EQ(load("sample:\n  id: \"\"\n").id, 0x300u);
  EXPECT_EQ(error_of("sample:\n  id: 0x800\n").first, "sample.id");
  EXPECT_EQ(error_of("sample:\n  id: 12z\n").first, "sample.id");
}

TEST_F(ParamsTest, Unsigned32BitSettingsTakeTheirWholeRangeAndNothingBeyond) {
  const auto load_seeded = [&](const std::string& text) {
    Seeded s;
    const File file(write(text));
    seeded_params().read(file, s);
    seeded_params().validate(file.path(), s);
    return s;
  };
  const auto error_of_seeded = [&](const std::string& text) -> std::pair<std::string, std::string> {
    try {
      load_seeded(text);
    } catch (const InputError& e) {
      return {e.where(), e.what()};
    }
    return {"", ""};
  };
  EXPECT_EQ(load_seeded("seeded:\n  seed: 4294967295\n").seed, 4294967295u);
  EXPECT_EQ(load_seeded("seeded:\n  seed: 0\n").seed, 0u);
  EXPECT_EQ(load_seeded("seeded:\n  frames: 100\n").frames, 100u);
  EXPECT_EQ(load_seeded("seeded:\n").seed, 1u);
  auto [where, what] = error_of_seeded("seeded:\n  seed: 4294967296\n");
  EXPECT_EQ(where, "seeded.seed");
  EXPECT_NE(what.find("expected an unsigned 32-bit integer, got '4294967296'"), std::string::npos) << what;
  std::tie(where, what) = error_of_seeded("seeded:\n  frames: 0\n");
  EXPECT_EQ(where, "seeded.frames");
  EXPECT_NE(what.find("expected an unsigned 32-bit integer in [1, 100] frames (one at least), got 0"),
            std::string::npos)
      << what;
  for (const char* text : {"seeded:\n  seed: -1\n", "seeded:\n  seed: 1.5\n", "seeded:\n  seed: one\n"}) {
    EXPECT_EQ(error_of_seeded(text).first, "seeded.seed") << text;
  }
  Seeded s;
  s.seed = 4294967295u;
  EXPECT_EQ(seeded_params().describe(s), "seeded: seed=4294967295, frames=4 frames");
}

TEST_F(ParamsTest, MissingSectionOrEmptyFileKeepsEveryDefault) {
  for (const char* text : {"", "# nothing\n", "sample:\n", "sample: {}\n"}) {
    const Sample s = load(text);
    EXPECT_EQ(s.count, 3) << text;
    EXPECT_EQ(s.name, "abc") << text;
  }
  const File file(write("other: 1\n"));
  EXPECT_FALSE(file.has_section("sample"));
  EXPECT_TRUE(File(write("sample:\n")).has_section("sample"));
  try {
    file.require_section("sample");
    FAIL() << "a required section that is missing must be an error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "sample");
    EXPECT_NE(std::string(e.what()).find("'sample:'"), std::string::npos) << e.what();
  }
}

TEST_F(ParamsTest, UnknownKeysAndSectionsListTheKnownOnes) {
  auto [where, what] = error_of("sample:\n  cuont: 2\n");
  EXPECT_EQ(where, "sample.cuont");
  EXPECT_NE(what.find("count, gain, enabled, name, shape, id, seed, low, high, depth_m, label"), std::string::npos)
      << what;
  std::tie(where, what) = error_of("samples:\n  count: 2\n");
  EXPECT_EQ(where, "samples");
  EXPECT_NE(what.find("expected one of: sample"), std::string::npos) << what;
  EXPECT_EQ(error_of("sample: 5\n").first, "sample");
  EXPECT_EQ(error_of("[1, 2]\n").first, "(top level)");
  EXPECT_EQ(error_of("sample: [1, 2\n").first, "line 2");
  // Keys that are lists or maps (found by tests/fuzz: yaml-cpp's conversion error escaped).
  std::tie(where, what) = error_of("? [a, b]\n: 1\n");
  EXPECT_EQ(where, "(top level)");
  EXPECT_NE(what.find("expected a plain name as key"), std::string::npos) << what;
  EXPECT_EQ(error_of("sample:\n  ? {a: 1}\n  : 2\n").first, "sample");
}

TEST_F(ParamsTest, WrongTypesNameTheFieldAndWhatWasExpected) {
  auto [where, what] = error_of("sample:\n  count: many\n");
  EXPECT_EQ(where, "sample.count");
  EXPECT_NE(what.find("expected an integer in [1, 10] frames (at least one frame), got 'many'"), std::string::npos)
      << what;
  EXPECT_NE(error_of("sample:\n  count: [2]\n").second.find("got a list"), std::string::npos);
  const std::vector<std::pair<const char*, const char*>> cases = {
      {"sample:\n  count: 2.5\n", "sample.count"},       {"sample:\n  count:\n", "sample.count"},
      {"sample:\n  gain: .nan\n", "sample.gain"},        {"sample:\n  gain: .inf\n", "sample.gain"},
      {"sample:\n  enabled: maybe\n", "sample.enabled"}, {"sample:\n  name: {a: 1}\n", "sample.name"},
      {"sample:\n  seed: -1\n", "sample.seed"},          {"sample:\n  id: [1]\n", "sample.id"},
  };
  for (const auto& [text, field] : cases) EXPECT_EQ(error_of(text).first, field) << text;
}

TEST_F(ParamsTest, EnumNamesAcceptAliasesAndListTheWrittenNames) {
  auto [where, what] = error_of("sample:\n  shape: oval\n");
  EXPECT_EQ(where, "sample.shape");
  EXPECT_NE(what.find("expected one of round, square, got 'oval'"), std::string::npos) << what;
  EXPECT_EQ(shape_names().name(Shape::kSquare), std::string("square"));
  Shape shape = Shape::kRound;
  EXPECT_TRUE(shape_names().parse("box", shape));
  EXPECT_EQ(shape, Shape::kSquare);
  EXPECT_FALSE(shape_names().parse("Box", shape));
}

TEST_F(ParamsTest, OutOfRangeValuesNameTheValueAndTheRange) {
  auto [where, what] = error_of("sample:\n  count: 11\n");
  EXPECT_EQ(where, "sample.count");
  EXPECT_NE(what.find("expected an integer in [1, 10] frames (at least one frame), got 11"), std::string::npos) << what;
  std::tie(where, what) = error_of("sample:\n  gain: 0\n");
  EXPECT_EQ(where, "sample.gain");
  EXPECT_NE(what.find("expected a number in (0, 1], got 0"), std::string::npos) << what;
  EXPECT_EQ(error_of("sample:\n  gain: 1\n").first, "");
  std::tie(where, what) = error_of("sample:\n  name: toolong\n");
  EXPECT_EQ(where, "sample.name");
  EXPECT_NE(what.find("a string of 1 to 5 characters, got toolong"), std::string::npos) << what;
  EXPECT_EQ(error_of("sample:\n  name: ''\n").first, "sample.name");
}

TEST_F(ParamsTest, RulesBetweenSettingsRunAfterTheRanges) {
  auto [where, what] = error_of("sample:\n  low: 5\n");
  EXPECT_EQ(where, "sample.high");
  EXPECT_NE(what.find("expected more than low, got 5"), std::string::npos) << what;
  EXPECT_EQ(error_of("sample:\n  low: -1\n  high: -2\n").first, "sample.low");  // the range first
}

TEST_F(ParamsTest, IncludedStructsAreReadInTheSectionAndValidatedUnderTheirOwnName) {
  auto [where, what] = error_of("sample:\n  depth_m: 10\n");
  EXPECT_EQ(where, "inner.depth_m");
  EXPECT_NE(what.find("expected an integer in [1, 9] m, got 10"), std::string::npos) << what;
  EXPECT_EQ(load("sample:\n  depth_m: 9\n  label: y\n").inner.label, "y");
  Sample s;
  s.inner.label = "";
  EXPECT_THROW(sample_params().validate("code", s), InputError);
}

TEST_F(ParamsTest, RangesCoverOpenClosedUnionsStepsAndOddNumbers) {
  EXPECT_TRUE(Range::any().contains(std::nan("")));
  EXPECT_FALSE(Range::at_least(0).contains(std::nan("")));
  EXPECT_FALSE(Range::at_least(0).contains(INFINITY));
  EXPECT_FALSE(Range::at_most(0).contains(-INFINITY));
  EXPECT_FALSE(Range::finite().contains(INFINITY));
  EXPECT_FALSE(Range::finite().contains(-INFINITY));
  EXPECT_FALSE(Range::finite().contains(std::nan("")));
  EXPECT_TRUE(Range::finite().contains(-1e300));
  EXPECT_EQ(detail::number_expectation("a number", Range::finite(), "px", ""), "a number (px)");
  const Range zero_or_ten = Range::at_least(10) | Range::value(0);
  EXPECT_TRUE(zero_or_ten.contains(0));
  EXPECT_FALSE(zero_or_ten.contains(5));
  EXPECT_TRUE(zero_or_ten.contains(10));
  EXPECT_EQ(zero_or_ten.text(), ">= 10 or 0");
  const Range sixteens = Range::closed(16, 1024).multiple_of(16);
  EXPECT_TRUE(sixteens.contains(64));
  EXPECT_FALSE(sixteens.contains(60));
  EXPECT_FALSE(sixteens.contains(1040));
  const Range odd = Range::closed(1, 11).odd();
  EXPECT_TRUE(odd.contains(5));
  EXPECT_FALSE(odd.contains(4));
  EXPECT_EQ(detail::number_expectation("an integer", odd, "", ""), "an odd integer in [1, 11]");
  EXPECT_EQ(detail::number_expectation("an integer", sixteens, "px", ""), "a multiple of 16 in [16, 1024] px");
  EXPECT_EQ(Range::right_open(0, 1).text(), "in [0, 1)");
  EXPECT_EQ(Range::open(0.001, 2).text(), "in (0.001, 2)");
  EXPECT_EQ(Range::above(1).text(), "> 1");
  EXPECT_EQ(Range::at_most(64).text(), "<= 64");
  EXPECT_FALSE(Range::open(0, 1).contains(0));
  EXPECT_FALSE(Range::open(0, 1).contains(1));
  EXPECT_TRUE(Range::left_open(0, 1).contains(1));
}

TEST_F(ParamsTest, DescribeEchoesEveryKeyWithItsUnit) {
  Sample s;
  s.name = "";
  EXPECT_EQ(sample_params().describe(s),
            "sample: count=3 frames, gain=0.5, enabled=true, name=\"\", shape=round, id=0x300, seed=1, low=1, high=5, "
            "depth_m=2, label=x (span 4)");
  EXPECT_EQ(detail::format_number(0.1), "0.1");
  EXPECT_EQ(detail::format_number(5.991), "5.991");
  EXPECT_EQ(detail::format_number(460.0), "460");
  EXPECT_EQ(detail::format_number(-0.25), "-0.25");
  EXPECT_EQ(detail::item("rate_hz", "20", "Hz"), "rate_hz=20");
  EXPECT_EQ(detail::item("speed_mps", "1", "m/s"), "speed_mps=1 m/s");
}

TEST_F(ParamsTest, MissingOrUnreadableFilesAreInputErrors) {
  EXPECT_THROW(File{"/nonexistent/params.yaml"}, InputError);
  EXPECT_THROW(File{dir_}, InputError);  // a folder
}

}  // namespace
}  // namespace agvslam::params
