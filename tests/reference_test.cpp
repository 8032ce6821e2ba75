// A calibration file is anyone's to edit: every value is range-checked where it is loaded, with
// the rules of Reference::validate(), and the error names the file and the field. Each case below
// once crashed or silently gave a wrong result.
#include "multislit/reference.h"
#include "multislit/sim/rdmap_synth.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

using namespace multislit;

namespace {

const Reference& good() {
  static const Reference ref = renderFloorReference(SensorConfig{}, MountConfig{});
  return ref;
}

const std::string& goodText() {
  static const std::string text = [] {
    const auto path = std::filesystem::temp_directory_path() / "multislit_reference_good.yaml";
    good().save(path.string());
    std::stringstream s;
    s << std::ifstream(path).rdbuf();
    return s.str();
  }();
  return text;
}

/// The error of loading the good calibration with the first match of `pattern` replaced.
std::string loadEdited(const std::string& name, const std::string& pattern,
                       const std::string& replacement) {
  const std::string text = std::regex_replace(goodText(), std::regex(pattern), replacement,
                                              std::regex_constants::format_first_only);
  EXPECT_NE(text, goodText()) << pattern;
  const auto path = std::filesystem::temp_directory_path() / ("multislit_reference_" + name);
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
  const auto path = std::filesystem::temp_directory_path() / "multislit_reference_good.yaml";
  goodText();
  const Reference back = Reference::load(path.string());
  EXPECT_EQ(back.slits.size(), good().slits.size());
  EXPECT_EQ(back.region_width, good().region_width);
}

TEST(Reference, OutOfRangeValuesAreRefusedNamingTheField) {
  struct Case {
    const char* name;
    const char* pattern;
    const char* replacement;
    const char* field;
  };
  const Case cases[] = {
      {"nan_width.yaml", "profile_width: [^\\n]*", "profile_width: .nan", "profile_width"},
      {"zero_width.yaml", "profile_width: [^\\n]*", "profile_width: 0", "profile_width"},
      {"neg_width.yaml", "profile_width: [^\\n]*", "profile_width: -1", "profile_width"},
      {"huge_width.yaml", "profile_width: [^\\n]*", "profile_width: 1717986000", "profile_width"},
      {"inf_width.yaml", "profile_width: [^\\n]*", "profile_width: .inf", "profile_width"},
      {"region.yaml", "\\nregion_width: [^\\n]*", "\nregion_width: 2000000000", "region_width"},
      {"dk_inf.yaml", "disparity_constant: [^\\n]*", "disparity_constant: .inf",
       "scale.disparity_constant"},
      {"f_inf.yaml", "   f: [^\\n]*", "   f: .inf", "scale.f"},
      {"first_row.yaml", "first_row: [0-9]+", "first_row: 2147483600", "slits[0].first_row"},
      {"big_image.yaml", "image_width: [0-9]+", "image_width: 20000", "image_width"},
      {"u_outside.yaml", "u: \\[ [^,]*,", "u: [ 5000.,", "slits[0].u[0]"},
      {"unknown.yaml", "profile_width:", "profil_width:", "unknown key 'profil_width'"},
      {"twice.yaml", "\nregion_width: ([0-9]+)", "\nregion_width: $1\nregion_width: 3",
       "'region_width' is given twice"},
  };
  for (const Case& c : cases) {
    const std::string error = loadEdited(c.name, c.pattern, c.replacement);
    EXPECT_NE(error.find(c.name), std::string::npos) << c.name << ": " << error;  // the file
    EXPECT_NE(error.find(c.field), std::string::npos) << c.name << ": " << error;
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
