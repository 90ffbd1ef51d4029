// The poses file of `objmap update-poses`: TUM-ordered lines, comments, and malformed lines
// reported with their line number.
#include "poses_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace objmap::cli {
namespace {

TEST(PosesFile, ParsesTumOrderCommentsAndBlankLines) {
  const std::string text =
      "# keyframe_id tx ty tz qx qy qz qw\n"
      "\n"
      "3 1.0 2.0 3.0 0 0 0 1\n"
      "7 -0.5 0 0.25 0 0 0.7071068 0.7071068   # quarter turn about z\n";
  std::vector<KeyframePoseLine> poses;
  std::string why;
  ASSERT_TRUE(ParsePosesText(text, &poses, &why)) << why;
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[0].keyframe_id, 3);
  EXPECT_EQ(poses[0].line, 3);
  EXPECT_TRUE(poses[0].T_W_C.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE(poses[0].T_W_C.linear().isIdentity(1e-12));
  EXPECT_EQ(poses[1].keyframe_id, 7);
  EXPECT_EQ(poses[1].line, 4);
  // The camera's x axis points along world y after a quarter turn about z.
  const Eigen::Vector3d x_W = poses[1].T_W_C.linear() * Eigen::Vector3d::UnitX();
  EXPECT_NEAR((x_W - Eigen::Vector3d::UnitY()).norm(), 0.0, 1e-6);
  EXPECT_NEAR(poses[1].T_W_C.linear().determinant(), 1.0, 1e-9);
}

TEST(PosesFile, NearlyUnitQuaternionsAreNormalized) {
  std::vector<KeyframePoseLine> poses;
  std::string why;
  ASSERT_TRUE(ParsePosesText("1 0 0 0 0 0 0.7072 0.7072\n", &poses, &why)) << why;
  const Eigen::Matrix3d R = poses[0].T_W_C.linear();
  EXPECT_NEAR((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
}

// Each malformed line fails with "line N: ..." naming what is wrong.
struct MalformedCase {
  std::string text;
  std::string expected;
};

TEST(PosesFile, MalformedLinesNameTheLine) {
  const std::string good = "1 0 0 0 0 0 0 1\n";
  const std::vector<MalformedCase> cases = {
      {good + "2 0 0 0 0 0 1\n", "line 2: expected 8 fields"},
      {good + "# c\n2 0 0 0 0 0 0 1 9\n", "line 3: expected 8 fields"},
      {"x 0 0 0 0 0 0 1\n", "line 1: keyframe_id must be a whole number >= 0, got 'x'"},
      {"1.5 0 0 0 0 0 0 1\n", "line 1: keyframe_id must be a whole number >= 0"},
      {"-1 0 0 0 0 0 0 1\n", "line 1: keyframe_id must be a whole number >= 0"},
      {good + "2 0 abc 0 0 0 0 1\n", "line 2: ty must be a finite number, got 'abc'"},
      {good + "2 0 0 nan 0 0 0 1\n", "line 2: tz must be a finite number, got 'nan'"},
      {good + "\n2 0 0 0 0 0 0 0\n", "line 3: quaternion (qx qy qz qw) has norm 0, not 1"},
      {good + "2 0 0 0 0 0 0 2\n", "line 2: quaternion (qx qy qz qw) has norm 2, not 1"},
      {good + "1 1 1 1 0 0 0 1\n", "line 2: keyframe 1 was already given on line 1"},
      {"# only a comment\n\n", "no poses"},
  };
  for (const MalformedCase& c : cases) {
    std::vector<KeyframePoseLine> poses;
    std::string why;
    EXPECT_FALSE(ParsePosesText(c.text, &poses, &why)) << c.text;
    EXPECT_EQ(why.rfind(c.expected, 0), 0u) << "got: " << why << "\nfor:\n" << c.text;
  }
}

TEST(PosesFile, FileErrorsStartWithThePath) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("objmap_poses_" + std::to_string(::getpid()) + ".txt"))
                               .string();
  std::ofstream(path) << "1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0\n";
  std::vector<KeyframePoseLine> poses;
  std::string why;
  EXPECT_FALSE(ReadPosesFile(path, &poses, &why));
  EXPECT_EQ(why, path + ": line 2: expected 8 fields (keyframe_id tx ty tz qx qy qz qw), got 7");
  std::filesystem::remove(path);
  EXPECT_FALSE(ReadPosesFile(path, &poses, &why));
  EXPECT_EQ(why, path + ": cannot be opened");
}

}  // namespace
}  // namespace objmap::cli
