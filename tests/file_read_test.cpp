// Reading an input file whole (src/internal/file_read.h): bounded, never blocking on a FIFO.
#include "file_read.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <fstream>
#include <stdexcept>
#include <string>

#include "multislit/sensor.h"
#include "test_support.h"

using multislit::detail::readWholeFile;

namespace {

std::string errorOf(const std::string& path, std::size_t limit) {
  try {
    readWholeFile(path, "sensor config", limit);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "read";
}

}  // namespace

// `mkfifo f.yaml; multislit simulate --sensor f.yaml` blocked for ever in open(), deaf to Ctrl-C.
TEST(FileRead, AFifoNobodyWritesToIsRefusedAtOnce) {
  const std::string path = tempPath("fifo.yaml");
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  const auto start = std::chrono::steady_clock::now();
  const std::string error = errorOf(path, 1000);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
  EXPECT_NE(error.find("sensor config '" + path + "' is a pipe or device that gave nothing"),
            std::string::npos)
      << error;
  try {
    multislit::SensorConfig::load(path);
    FAIL() << "a FIFO was loaded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(FileRead, FilesAndStreamsAreCappedFoldersAndMissingFilesNamed) {
  const std::string path = tempPath("ten.yaml");
  std::ofstream(path) << "0123456789";
  EXPECT_EQ(readWholeFile(path, "x", 10), "0123456789");
  EXPECT_NE(errorOf(path, 9).find("is 10 bytes, more than the limit of 9 bytes"),
            std::string::npos);
  // A device cannot be sized first: it is read up to the limit.
  EXPECT_NE(errorOf("/dev/zero", 1 << 20).find("holds more than the limit of 1048576 bytes"),
            std::string::npos);
  EXPECT_NE(errorOf(tempPath(""), 10).find("is a folder, not a file"), std::string::npos);
  EXPECT_NE(errorOf(tempPath("missing.yaml"), 10).find("cannot be read: No such file"),
            std::string::npos);
}
