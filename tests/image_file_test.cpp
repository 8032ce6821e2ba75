// Image files: the size read from the header of every format the commands take, before decoding;
// images too large, cut, of other formats or types refused naming the file.
#include "multislit/image_file.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

using namespace multislit;

namespace {

std::string readError(const std::string& path) {
  try {
    readMonoImage(path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "read";
}

std::vector<char> fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

TEST(ImageFile, HeaderSizeOfEveryFormatMatchesTheDecodedImage) {
  cv::Mat image(37, 53, CV_8UC1);
  cv::randu(image, 0, 255);
  const cv::Mat wide(21, 70, CV_16UC1, cv::Scalar(1000));
  for (const std::string ext : {"png", "pgm", "bmp", "tif", "jpg"}) {
    const std::string path = tempPath("size." + ext);
    ASSERT_TRUE(cv::imwrite(path, image)) << ext;
    const auto size = imageFileSize(path);
    ASSERT_TRUE(size.has_value()) << ext;
    EXPECT_EQ(*size, cv::Size(53, 37)) << ext;
    EXPECT_EQ(readMonoImage(path).size(), cv::Size(53, 37)) << ext;
    std::filesystem::remove(path);
  }
  for (const std::string ext : {"png", "pgm", "tif"}) {  // 16-bit images
    const std::string path = tempPath("wide." + ext);
    ASSERT_TRUE(cv::imwrite(path, wide)) << ext;
    EXPECT_EQ(imageFileSize(path), cv::Size(70, 21)) << ext;
    EXPECT_EQ(readMonoImage(path).depth(), CV_16U) << ext;
    std::filesystem::remove(path);
  }
}

TEST(ImageFile, TooLargeCutForeignAndColourImagesAreRefusedNamingTheFile) {
  // A PNG whose header says 30000 x 30000 (1.8 GB decoded): refused from its 33-byte header.
  const std::string huge = tempPath("huge.png");
  cv::imwrite(huge, cv::Mat(1, 1, CV_16UC1, cv::Scalar(0)));
  std::vector<char> bytes = fileBytes(huge);
  for (int k = 0; k < 2; ++k) {  // IHDR width and height, big-endian, at bytes 16 and 20
    const std::uint32_t v = 30000;
    for (int b = 0; b < 4; ++b) bytes[16 + 4 * k + b] = static_cast<char>(v >> (24 - 8 * b));
  }
  std::ofstream(huge, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  EXPECT_EQ(imageFileSize(huge), cv::Size(30000, 30000));
  EXPECT_NE(readError(huge).find("30000x30000 px, more than the limit of 16384 px a side"),
            std::string::npos)
      << readError(huge);
  EXPECT_NE(readError(huge).find(huge), std::string::npos);

  const std::string cut = tempPath("cut.png");
  std::ofstream(cut, std::ios::binary).write(bytes.data(), 12);
  EXPECT_FALSE(imageFileSize(cut).has_value());
  EXPECT_NE(readError(cut).find("corrupt or not a PNG"), std::string::npos) << readError(cut);

  const std::string text = tempPath("text.png");
  std::ofstream(text) << "not an image at all\n";
  EXPECT_NE(readError(text).find("corrupt or not a PNG"), std::string::npos) << readError(text);

  const std::string colour = tempPath("colour.png");
  cv::imwrite(colour, cv::Mat(8, 8, CV_8UC3, cv::Scalar(1, 2, 3)));
  EXPECT_NE(readError(colour).find("must be 8- or 16-bit grey"), std::string::npos)
      << readError(colour);
  EXPECT_NE(readError(tempPath("missing.png")).find("does not exist"), std::string::npos);
  for (const std::string& p : {huge, cut, text, colour}) std::filesystem::remove(p);
}
