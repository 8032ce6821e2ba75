// A calibration file is anyone's to edit: every value is range-checked where it is loaded, with
// the rules of Reference::validate(), and the error names the file and the field. Each case below
// once crashed or silently gave a wrong result.
#include "multislit/reference.h"
#include "default_reference.h"
#include "multislit/sim/rdmap_synth.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

using namespace multislit;

namespace {

const Reference& good() { return test::defaultReference(); }

const std::string& goodText() {
  static const std::string text = [] {
    const auto path = std::filesystem::path(tempPath("multislit_reference_good.yaml"));
    good().save(path.string());
    std::stringstream s;
    s << std::ifstream(path).rdbuf();
    return s.str();
  }();
  return text;
}

/// The good calibration with the first line that starts (after its indent) with `key` + ":"
/// replaced by `line` (the indent kept); `line` empty: the line is given twice.
std::string edited(const std::string& key, const std::string& line) {
  std::string text = goodText();
  std::size_t at = 0;
  for (;;) {
    at = text.find(key + ":", at);
    if (at == std::string::npos) return text;
    std::size_t start = at;
    while (start > 0 && text[start - 1] == ' ') --start;
    if (start == 0 || text[start - 1] == '\n') break;
    ++at;
  }
  const std::size_t end = text.find('\n', at);
  const std::string old = text.substr(at, end - at);
  text.replace(at, end - at, line.empty() ? old + "\n" + old : line);
  return text;
}

/// The error of loading `text` written to a file called `name` ("" when it loads).
std::string loadError(const std::string& name, const std::string& text) {
  EXPECT_NE(text, goodText()) << name;
  const auto path = std::filesystem::path(tempPath("multislit_reference_" + name));
  std::ofstream(path) << text;
  try {
    Reference::load(path.string());
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Reference, TheGoodCalibrationLoadsAndValidates) {
  EXPECT_NO_THROW(good().validate());
  const auto path = std::filesystem::path(tempPath("multislit_reference_good.yaml"));
  goodText();
  const Reference back = Reference::load(path.string());
  EXPECT_EQ(back.slits.size(), good().slits.size());
  EXPECT_EQ(back.region_width, good().region_width);
}

TEST(Reference, OutOfRangeValuesAreRefusedNamingTheField) {
  struct Case {
    const char* name;
    const char* key;
    const char* line;  // "": the key's line twice
    const char* field;
  };
  const Case cases[] = {
      {"nan_width.yaml", "profile_width", "profile_width: .nan", "profile_width"},
      {"zero_width.yaml", "profile_width", "profile_width: 0", "profile_width"},
      {"neg_width.yaml", "profile_width", "profile_width: -1", "profile_width"},
      {"huge_width.yaml", "profile_width", "profile_width: 1717986000", "profile_width"},
      {"inf_width.yaml", "profile_width", "profile_width: .inf", "profile_width"},
      {"region.yaml", "region_width", "region_width: 2000000000", "region_width"},
      {"dk_inf.yaml", "disparity_constant", "disparity_constant: .inf", "scale.disparity_constant"},
      {"f_inf.yaml", "f", "f: .inf", "scale.f"},
      // Finite, but no sensor has them: rdmap wrote every point at +-inf, map decided on them.
      {"cx_huge.yaml", "cx", "cx: 1e308", "scale.cx must lie inside the image"},
      {"cy_outside.yaml", "cy", "cy: -5", "scale.cy must lie inside the image"},
      {"f_tiny.yaml", "f", "f: 1e-320", "scale.f must be in [1, 1e6] px"},
      {"dk_huge.yaml", "disparity_constant", "disparity_constant: 1e308",
       "scale.disparity_constant over f (the baseline) must be in [0.001, 1] m, not 9.375e+304 m"},
      {"first_row.yaml", "first_row", "first_row: 2147483600", "slits[0].first_row"},
      {"big_image.yaml", "image_width", "image_width: 20000", "image_width"},
      {"unknown.yaml", "profile_width", "profil_width: 9.5", "unknown key 'profil_width'"},
      {"twice.yaml", "region_width", "", "'region_width' is given twice"},
  };
  for (const Case& c : cases) {
    const std::string error = loadError(c.name, edited(c.key, c.line));
    EXPECT_NE(error.find(c.name), std::string::npos) << c.name << ": " << error;  // the file
    EXPECT_NE(error.find(c.field), std::string::npos) << c.name << ": " << error;
  }
  Reference behind = good();
  ASSERT_FALSE(behind.slits[0].u_inf.empty());
  std::size_t j = 0;
  while (!std::isfinite(behind.slits[0].u_inf[j])) ++j;
  behind.slits[0].u_inf[j] = behind.slits[0].u[j] + 1.0f;  // the reference point behind the camera
  try {
    behind.validate();
    FAIL() << "a reference point behind the sensor was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("slits[0].u_inf[" + std::to_string(j) + "]"),
              std::string::npos)
        << e.what();
  }
  // Every other slit's reference points moved 40 % farther: no longer one plane.
  Reference bent = good();
  for (std::size_t k = 1; k < bent.slits.size(); k += 2)
    for (std::size_t i = 0; i < bent.slits[k].u_inf.size(); ++i)
      bent.slits[k].u_inf[i] =
          bent.slits[k].u[i] - (bent.slits[k].u[i] - bent.slits[k].u_inf[i]) / 1.4f;
  try {
    bent.validate();
    FAIL() << "reference points off one plane were accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("mm rms off one plane"), std::string::npos) << e.what();
  }
  Reference outside = good();
  outside.slits[0].u[0] = 5000.0f;  // a column beyond the 1296 px image
  try {
    outside.validate();
    FAIL() << "a column outside the image was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("slits[0].u[0]"), std::string::npos) << e.what();
  }
}

TEST(Reference, TheSameSlitTwiceOrOverlappingRegionsAreRefused) {
  Reference repeated = good();
  repeated.slits.assign(15, good().slits[7]);
  try {
    repeated.validate();
    FAIL() << "15 copies of one slit were accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("slits[1] must lie at least region_width"),
              std::string::npos)
        << e.what();
  }
  Reference wide = good();
  wide.region_width = 2 * good().region_width;  // regions of neighbours would overlap
  EXPECT_THROW(wide.validate(), std::invalid_argument);
  EXPECT_THROW(repeated.save("/tmp/multislit_never_written.yaml"), std::invalid_argument);
}
