// The GenICam description the emulated camera serves (private to the simulator): Aravis's fake
// camera's own, with the features a real sensor's camera has and it lacks.
#pragma once

#include <cstdint>
#include <string>

namespace multislit::emulator {

/// Registers of the added features, in the fake camera's memory beyond the GigE Vision bootstrap
/// registers (0x0000-0x0fff) and its own (0x100-0x30c).
constexpr std::uint32_t kPtpEnableRegister = 0x8000;  ///< 1: PtpEnable on
constexpr std::uint32_t kPtpStatusRegister = 0x8004;  ///< PtpStatus: 0 Disabled, 2 Slave
constexpr std::uint32_t kPtpStatusSlave = 2;

/// Aravis's fake camera description with PixelFormat Mono12 and the PTP features PtpEnable and
/// PtpStatus added. Throws std::runtime_error when this Aravis's description lacks what they are
/// added to.
std::string emulatorGenicam(const std::string& serial);

/// A file holding `text` while it lives (the fake camera reads its description from a file).
class TemporaryFile {
 public:
  explicit TemporaryFile(const std::string& text);
  ~TemporaryFile();
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace multislit::emulator
