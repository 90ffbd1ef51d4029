// The argument parser of the `objmap` commands: values, lists, and the errors users see.
#include "arguments.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace objmap::cli {
namespace {

// Owns argv-style words for the parser.
class Words {
 public:
  explicit Words(std::vector<std::string> words) : words_(std::move(words)) {
    for (std::string& word : words_) pointers_.push_back(word.data());
  }
  int argc() const { return static_cast<int>(pointers_.size()); }
  char** argv() { return pointers_.data(); }

 private:
  std::vector<std::string> words_;
  std::vector<char*> pointers_;
};

Arguments Parse(Words words) {
  return Arguments(words.argc(), words.argv(), {"--class", "--limit", "--min-confidence"},
                   {"--json"}, {{"--region", 6}, {"--near", 3}});
}

TEST(Arguments, ReadsValuesListsSwitchesAndPositionals) {
  Arguments args = Parse(Words({"pos", "--class", "dining table", "--region", "-1", "-2", "0", "1",
                                "2", "1.5", "--json", "--limit", "7"}));
  ASSERT_EQ(args.error(), "");
  EXPECT_EQ(args.positional(), std::vector<std::string>{"pos"});
  EXPECT_EQ(args.Get("--class", ""), "dining table");
  EXPECT_TRUE(args.Has("--json"));
  EXPECT_TRUE(args.Has("--region"));
  EXPECT_FALSE(args.Has("--near"));
  EXPECT_EQ(args.GetNumbers("--region"), (std::vector<double>{-1, -2, 0, 1, 2, 1.5}));
  EXPECT_TRUE(args.GetNumbers("--near").empty());
  EXPECT_EQ(args.GetInteger("--limit", 0, 0), 7);
  EXPECT_EQ(args.GetInteger("--absent", 42, 0), 42);
  EXPECT_EQ(args.error(), "");
}

TEST(Arguments, MissingValueIsNamed) {
  EXPECT_EQ(Parse(Words({"--class"})).error(), "--class needs a value");
  // The next word is another option, not the value.
  EXPECT_EQ(Parse(Words({"--class", "--json"})).error(), "--class needs a value");
  EXPECT_EQ(Parse(Words({"--region", "0", "0", "0", "1", "1"})).error(), "--region needs 6 values");
  EXPECT_EQ(Parse(Words({"--near", "0", "--json", "1"})).error(), "--near needs 3 values");
}

TEST(Arguments, UnknownOptionIsNamed) {
  EXPECT_EQ(Parse(Words({"--colour", "red"})).error(), "unknown option --colour");
}

TEST(Arguments, BadNumbersAreNamedWithTheirFlag) {
  Arguments args = Parse(Words({"--min-confidence", "high"}));
  EXPECT_EQ(args.GetNumber("--min-confidence", 0.0), 0.0);
  EXPECT_EQ(args.error(), "--min-confidence expects a number, got 'high'");

  args = Parse(Words({"--min-confidence", "nan"}));
  (void)args.GetNumber("--min-confidence", 0.0);
  EXPECT_EQ(args.error(), "--min-confidence expects a number, got 'nan'");

  args = Parse(Words({"--limit", "2.5"}));
  EXPECT_EQ(args.GetInteger("--limit", 0, 0), 0);
  EXPECT_EQ(args.error(), "--limit expects a whole number >= 0, got '2.5'");

  args = Parse(Words({"--limit", "-1"}));
  (void)args.GetInteger("--limit", 0, 0);
  EXPECT_EQ(args.error(), "--limit expects a whole number >= 0, got '-1'");

  args = Parse(Words({"--region", "0", "0", "0", "1", "x", "1"}));
  EXPECT_TRUE(args.GetNumbers("--region").empty());
  EXPECT_EQ(args.error(), "--region expects numbers, got 'x' as value 5");
}

TEST(Arguments, PositionalNumbersAreNamed) {
  Arguments args = Parse(Words({"0", "1e-2", "z"}));
  EXPECT_EQ(args.PositionalNumber(0, "X0"), 0.0);
  EXPECT_DOUBLE_EQ(args.PositionalNumber(1, "Y0"), 0.01);
  EXPECT_EQ(args.error(), "");
  (void)args.PositionalNumber(2, "Z0");
  EXPECT_EQ(args.error(), "Z0 expects a number, got 'z'");

  args = Parse(Words({"0"}));
  (void)args.PositionalNumber(3, "X1");
  EXPECT_EQ(args.error(), "missing X1");
}

TEST(Arguments, FirstErrorIsKept) {
  Arguments args = Parse(Words({"--limit", "many", "--min-confidence", "x"}));
  (void)args.GetInteger("--limit", 0, 0);
  (void)args.GetNumber("--min-confidence", 0.0);
  EXPECT_EQ(args.error(), "--limit expects a whole number >= 0, got 'many'");
}

TEST(ParseNumbers, WholeTextOnly) {
  double number = 0.0;
  EXPECT_TRUE(ParseNumber("-3.25", &number));
  EXPECT_EQ(number, -3.25);
  EXPECT_FALSE(ParseNumber("3.25m", &number));
  EXPECT_FALSE(ParseNumber("", &number));
  EXPECT_FALSE(ParseNumber("inf", &number));
  std::int64_t integer = 0;
  EXPECT_TRUE(ParseInteger("9007199254740993", &integer));
  EXPECT_EQ(integer, 9007199254740993LL);
  EXPECT_FALSE(ParseInteger("12 ", &integer));
  EXPECT_FALSE(ParseInteger("99999999999999999999", &integer));
}

}  // namespace
}  // namespace objmap::cli
