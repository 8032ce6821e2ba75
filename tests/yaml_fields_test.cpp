// A config's YAML keys in one table (src/internal/yaml_fields.h): the text written from a table,
// the values read back, the key list checkKeys() takes, and errors naming the key.
#include "yaml_fields.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace multislit {
namespace {

struct Toy {
  int count = 3;
  unsigned seed = 7;
  double length = 0.25;
  std::string label = "a";
  std::vector<float> row;
  Eigen::Vector3d point = Eigen::Vector3d(1, 2, 3);
  LensDistortion distortion;
  bool flag = false;  // written by hand as yes / no
};

const Field<Toy> kToyKeys[] = {
    {"count", &Toy::count},
    {"seed", &Toy::seed},
    {"length", &Toy::length},
    {"label", &Toy::label},
    {"row", &Toy::row},
    {"point", &Toy::point},
    {"distortion", &Toy::distortion},
    {"flag", Codec<Toy>{[](const cv::FileNode& node, const char* key, Toy& t) {
                          std::string text = t.flag ? "yes" : "no";
                          readField(node, key, text);
                          t.flag = text == "yes";
                        },
                        [](cv::FileStorage& fs, const char* key, const Toy& t) {
                          fs << key << (t.flag ? "yes" : "no");
                        }}}};

std::string written(const Toy& toy) {
  cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  writeFields(fs, kToyKeys, toy);
  return fs.releaseAndGetString();
}

Toy readBack(const std::string& text) {
  const cv::FileStorage fs = openYamlText(text, "toy.yaml", "toy");
  Toy toy;
  readFields(fs.root(), kToyKeys, toy);
  return toy;
}

}  // namespace

TEST(YamlFields, WritesTheTableInOrderAndAPinholeWithoutItsCoefficients) {
  const std::string text = written(Toy{});
  EXPECT_EQ(text,
            "%YAML:1.0\n---\ncount: 3\nseed: 7.\nlength: 2.5000000000000000e-01\nlabel: a\n"
            "point: [ 1., 2., 3. ]\nflag: no\n");
}

TEST(YamlFields, ReadsBackWhatItWrote) {
  Toy toy;
  toy.count = -12;
  toy.seed = 4000000000u;  // beyond OpenCV's int: written as a real
  toy.length = 1.0 / 3.0;
  toy.label = "b c";
  toy.row = {1.5f, -2.25f};
  toy.point = Eigen::Vector3d(-0.5, 0.125, 9);
  toy.distortion.k1 = 0.1, toy.distortion.p2 = -0.002, toy.distortion.k6 = 3;
  toy.flag = true;
  const std::string text = written(toy);
  EXPECT_NE(text.find("k1: "), std::string::npos) << text;
  const Toy back = readBack(text);
  EXPECT_EQ(back.count, -12);
  EXPECT_EQ(back.seed, 4000000000u);
  EXPECT_EQ(back.length, 1.0 / 3.0);
  EXPECT_EQ(back.label, "b c");
  EXPECT_EQ(back.row, (std::vector<float>{1.5f, -2.25f}));
  EXPECT_EQ(back.point, Eigen::Vector3d(-0.5, 0.125, 9));
  EXPECT_EQ(back.distortion.k1, 0.1);
  EXPECT_EQ(back.distortion.p2, -0.002);
  EXPECT_EQ(back.distortion.k6, 3);
  EXPECT_EQ(back.distortion.k2, 0);
  EXPECT_TRUE(back.flag);
}

TEST(YamlFields, AbsentKeysKeepTheirValues) {
  const Toy back = readBack("%YAML:1.0\n---\nlength: 2\n");
  EXPECT_EQ(back.length, 2.0);
  EXPECT_EQ(back.count, 3);
  EXPECT_EQ(back.label, "a");
  EXPECT_EQ(back.point, Eigen::Vector3d(1, 2, 3));
  EXPECT_FALSE(back.flag);
}

TEST(YamlFields, KeysListTheDistortionsCoefficientsInItsPlace) {
  EXPECT_EQ(keysOf(kToyKeys),
            (std::vector<std::string>{"count", "seed", "length", "label", "row", "point", "k1",
                                      "k2", "p1", "p2", "k3", "k4", "k5", "k6", "flag"}));
  const Field<Toy> more[] = {{"extra", &Toy::count}};
  EXPECT_EQ(keysOf(more, more), (std::vector<std::string>{"extra", "extra"}));
}

TEST(YamlFields, AValueOfTheWrongTypeIsAnErrorNamingItsKey) {
  const auto error = [](const std::string& entry) {
    try {
      readBack("%YAML:1.0\n---\n" + entry + "\n");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error("count: 2.5"), "field 'count' must be an integer in [-2147483648, 2147483647]");
  EXPECT_EQ(error("seed: -1"), "field 'seed' must be an integer in [0, 4294967295]");
  EXPECT_EQ(error("length: abc"), "field 'length' must be a number");
  EXPECT_EQ(error("label: 5"), "field 'label' must be a string");
  EXPECT_EQ(error("point: [1, 2]"), "field 'point' must be a list of 3 numbers");
  EXPECT_EQ(error("point: [1, x, 2]"), "field 'point' must be a list of 3 numbers");
  EXPECT_EQ(error("k3: [1]"), "field 'k3' must be a number");
}

}  // namespace multislit
