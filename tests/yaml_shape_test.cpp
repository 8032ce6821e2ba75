// The check of a config file before OpenCV's YAML parser sees it (src/internal/yaml_shape.h):
// nesting counted as the parser nests, quotes as the parser reads them, integers it would wrap.
#include "yaml_shape.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

using multislit::yamlShapeProblem;

namespace {

constexpr const char* kHead = "%YAML:1.0\n---\n";

std::string repeat(const std::string& s, int n) {
  std::string out;
  for (int k = 0; k < n; ++k) out += s;
  return out;
}

bool says(const std::string& problem, const std::string& part) {
  return problem.find(part) != std::string::npos;
}

}  // namespace

// Block sequences `- - - ... 1` nest one level per dash (the parser overflowed its stack at
// 50 000); so do maps begun on one line (`a: b: c: ...`).
TEST(YamlShape, BlockCollectionsBegunOnOneLineCountAsNesting) {
  const std::string dashes =
      yamlShapeProblem(std::string(kHead) + "a:\n  " + repeat("- ", 50000) + "1\n");
  EXPECT_TRUE(says(dashes, "line 4 begins 50000 nested collections")) << dashes;
  const std::string tight =
      yamlShapeProblem(std::string(kHead) + "a:\n  " + std::string(50000, '-') + "1\n");
  EXPECT_TRUE(says(tight, "nested collections")) << tight;
  const std::string keys = yamlShapeProblem(std::string(kHead) + repeat("k: ", 100) + "1\n");
  EXPECT_TRUE(says(keys, "line 3 begins 100 nested collections")) << keys;
  EXPECT_EQ(yamlShapeProblem(std::string(kHead) + "a:\n  " + repeat("- ", 60) + "1\n"), "");
}

// An apostrophe inside a plain value is a letter: it left the old check "inside a string" for
// the rest of the file, and 200 000 brackets after it overflowed the parser's stack.
TEST(YamlShape, AQuoteOpensAStringOnlyWhereAValueBegins) {
  const std::string apostrophe = yamlShapeProblem(
      std::string(kHead) + "camera_id: it's\nx: " + std::string(200000, '[') + "\n");
  EXPECT_TRUE(says(apostrophe, "nested 200000 brackets deep")) << apostrophe;
  // Brackets inside real strings are text, escapes included.
  EXPECT_EQ(yamlShapeProblem(std::string(kHead) + "a: '" + std::string(100, '[') + "'\n"), "");
  EXPECT_EQ(yamlShapeProblem(std::string(kHead) + "a: 'it''s " + std::string(100, '[') + "'\n"),
            "");
  EXPECT_EQ(yamlShapeProblem(std::string(kHead) + "a: \"x\\\"" + std::string(100, '[') + "\"\n"),
            "");
  // A string ends with its line, as the parser reads it.
  const std::string unclosed =
      yamlShapeProblem(std::string(kHead) + "a: 'x\nb: " + std::string(100, '[') + "\n");
  EXPECT_TRUE(says(unclosed, "nested 100 brackets deep")) << unclosed;
  // A block key is read raw up to ':', a quote in it too.
  const std::string key =
      yamlShapeProblem(std::string(kHead) + "a: 1\n'b: " + std::string(100, '[') + "\n");
  EXPECT_TRUE(says(key, "nested 100 brackets deep")) << key;
  // So is a flow map's key after ',': its ']' closes nothing.
  const std::string flow_key =
      yamlShapeProblem(std::string(kHead) + "a: {b: 1, " + std::string(100, ']') + ": " +
                       std::string(100, '[') + "\n");
  EXPECT_TRUE(says(flow_key, "nested 101 brackets deep")) << flow_key;
  // A comment begins where a token does.
  EXPECT_EQ(yamlShapeProblem(std::string(kHead) + "# [[[[\na: 1 # " + std::string(100, '[') + "\n"),
            "");
}

// OpenCV reads an integer as `int`: 4294968592 became 1296, 010 became 8.
TEST(YamlShape, IntegersOutsideThe32BitRangeOrWithALeadingZeroAreRefusedNamingTheLine) {
  const std::string wide = yamlShapeProblem(std::string(kHead) + "camera:\n  width: 4294968592\n");
  EXPECT_TRUE(says(wide, "line 4 'width: 4294968592': the integer 4294968592 is outside")) << wide;
  const std::string in_list = yamlShapeProblem(std::string(kHead) + "a: [1, -4294967296]\n");
  EXPECT_TRUE(says(in_list, "the integer -4294967296 is outside")) << in_list;
  const std::string huge = yamlShapeProblem(std::string(kHead) + "a: " + std::string(40, '9'));
  EXPECT_TRUE(says(huge, "is outside")) << huge;
  const std::string octal = yamlShapeProblem(std::string(kHead) + "first_row: 010\n");
  EXPECT_TRUE(says(octal, "the integer 010 begins with 0")) << octal;
  EXPECT_EQ(yamlShapeProblem(std::string(kHead) +
                             "a: 2147483647\nb: -2147483648\nc: 1e308\nd: 0\ne: 0.5\nf: 0x10\n"),
            "");
}

// The files the tools write and the committed ones pass.
TEST(YamlShape, CommittedConfigFilesPass) {
  for (const auto& entry : std::filesystem::recursive_directory_iterator(MULTISLIT_DATA_DIR)) {
    if (entry.path().extension() != ".yaml") continue;
    std::ifstream in(entry.path());
    std::stringstream text;
    text << in.rdbuf();
    EXPECT_EQ(yamlShapeProblem(text.str()), "") << entry.path();
  }
}
