#include "camera_options.h"

#include "config_options.h"

#include <string>

namespace multislit::apps {

namespace {
const char* const kCameraOptions[] = {"exposure", "gain", "pixel-format", "ptp-utc-offset"};
}  // namespace

void addCameraOptions(cli::ArgParser& args) {
  const AravisConfig d;
  args.option("exposure", defaultText(d.exposure_us),
              "exposure time, the camera's ExposureTime (or ExposureTimeAbs) [us]; 0: keep the "
              "camera's");
  args.option("gain", defaultText(d.gain_db),
              "gain, the camera's Gain [dB] (GainRaw's units on cameras without Gain); "
              "negative: keep the camera's");
  args.option("pixel-format", pixelFormatName(d.pixel_format),
              "Mono8, Mono12 (16-bit images of values 0..4095: calibrate with --full-scale 4095) "
              "or Mono16");
  args.option("ptp-utc-offset", defaultText(d.ptp_utc_offset_s),
              "how far the camera's PTP clock runs ahead of UTC, subtracted from its stamps [s]: "
              "37 for PTP's default time scale TAI, 0 for a camera on UTC; host stamps keep "
              "their value");
}

void refuseCameraOptionsWithoutCamera(const cli::ArgParser& args) {
  for (const char* name : kCameraOptions)
    if (args.given(name))
      throw cli::UsageError("--" + std::string(name) + " sets a live camera: it needs --camera");
}

AravisConfig cameraSettingsFromArgs(const cli::ArgParser& args, AravisConfig config) {
  config.exposure_us = args.number("exposure");
  config.gain_db = args.number("gain");
  config.ptp_utc_offset_s = args.number("ptp-utc-offset");
  const std::optional<PixelFormat> format = parsePixelFormat(args.str("pixel-format"));
  if (!format)
    throw cli::UsageError("--pixel-format must be Mono8, Mono12 or Mono16, not '" +
                          args.str("pixel-format") + "'");
  config.pixel_format = *format;
  validateOptions(
      config, args,
      {{"exposure_us", "exposure"}, {"gain_db", "gain"}, {"ptp_utc_offset_s", "ptp-utc-offset"}});
  return config;
}

}  // namespace multislit::apps
