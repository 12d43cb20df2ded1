#include <gtest/gtest.h>

#include "agvslam/io/objects_io.h"
#include "io_test_util.h"

namespace agvslam::io {
namespace {
using testing::expect_input_error;
using testing::TempDir;

TEST(ObjectsIo, ReadsFramesObjectsAndInclusiveBoxes) {
  TempDir dir;
  const std::string path = dir.write("objects.txt",
                                     "# frame id class moving x_min y_min x_max y_max\n"
                                     "0 1 person 1 10 20 39 119\n"
                                     "0 2 forklift 0 300 100 500 300\n"
                                     "\n"
                                     "5 1 person 1 12 20 41 119\n");
  const auto objects = read_objects_file(path);
  ASSERT_EQ(objects.size(), 2u);
  ASSERT_EQ(objects.at(0).size(), 2u);
  EXPECT_EQ(objects.at(0)[0].id, 1);
  EXPECT_EQ(objects.at(0)[0].object_class, "person");
  EXPECT_TRUE(objects.at(0)[0].moving);
  EXPECT_EQ(objects.at(0)[0].box, cv::Rect(10, 20, 30, 100));
  EXPECT_FALSE(objects.at(0)[1].moving);
  EXPECT_EQ(objects.at(5)[0].box.x, 12);
  EXPECT_EQ(objects.count(3), 0u);
}

TEST(ObjectsIo, BadLinesNameTheFileLineAndExpectation) {
  TempDir dir;
  expect_input_error([&] { read_objects_file(dir.write("a.txt", "0 1 person 1 10 20 39\n")); },
                     {"a.txt", "line 1", "expected 8 fields"});
  expect_input_error([&] { read_objects_file(dir.write("b.txt", "# c\n0 1 person yes 10 20 39 50\n")); },
                     {"b.txt", "line 2", "moving"});
  expect_input_error([&] { read_objects_file(dir.write("c.txt", "0 1 person 1 40 20 39 50\n")); },
                     {"c.txt", "line 1", "x_min <= x_max"});
  expect_input_error([&] { read_objects_file(dir.write("d.txt", "0 1 person 2 10 20 39 50\n")); },
                     {"d.txt", "moving to be 0 or 1"});
  expect_input_error([&] { read_objects_file(dir.file("missing.txt")); }, {"missing.txt", "not found"});
}

}  // namespace
}  // namespace agvslam::io
