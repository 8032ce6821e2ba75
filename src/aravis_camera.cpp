// Opening and setting up a camera for AravisSource: by address or USB identity, never by
// network discovery; its identity, region and pixel format checked against what was asked.
#include "aravis_camera.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <utility>

namespace multislit::aravis {

namespace {

constexpr int kGvcpPort = 3956;

// The local address the kernel routes to `device` from (connecting a UDP socket sends nothing).
std::string localAddressFor(const std::string& device) {
  if (device.rfind("127.", 0) == 0) return "127.0.0.1";
  sockaddr_in remote{};
  remote.sin_family = AF_INET;
  remote.sin_port = htons(kGvcpPort);
  if (inet_pton(AF_INET, device.c_str(), &remote.sin_addr) != 1)
    throw std::invalid_argument("AravisConfig.camera '" + device + "' is not an IPv4 address");
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) throw std::runtime_error("cannot create a socket to find the route to " + device);
  sockaddr_in local{};
  socklen_t length = sizeof local;
  const bool ok = connect(fd, reinterpret_cast<const sockaddr*>(&remote), sizeof remote) == 0 &&
                  getsockname(fd, reinterpret_cast<sockaddr*>(&local), &length) == 0;
  close(fd);
  char text[INET_ADDRSTRLEN] = {};
  if (!ok || inet_ntop(AF_INET, &local.sin_addr, text, sizeof text) == nullptr)
    throw std::runtime_error("no route to camera " + device);
  return text;
}

ArvPixelFormat asked(PixelFormat format) {
  switch (format) {
    case PixelFormat::Mono8:
      return ARV_PIXEL_FORMAT_MONO_8;
    case PixelFormat::Mono12:
      return ARV_PIXEL_FORMAT_MONO_12;
    case PixelFormat::Mono16:
      break;
  }
  return ARV_PIXEL_FORMAT_MONO_16;
}

// A number the camera is set to (exposure, gain): its GenICam feature, the config's field, the
// unit and Aravis's calls for it.
struct CameraSetting {
  const char* feature;
  const char* field;
  const char* unit;
  gboolean (*available)(ArvCamera*, GError**);
  void (*bounds)(ArvCamera*, double*, double*, GError**);
  void (*set)(ArvCamera*, double, GError**);
  double (*get)(ArvCamera*, GError**);
};

const CameraSetting kExposure{"ExposureTime (or ExposureTimeAbs)",
                              "exposure_us",
                              "us",
                              arv_camera_is_exposure_time_available,
                              arv_camera_get_exposure_time_bounds,
                              arv_camera_set_exposure_time,
                              arv_camera_get_exposure_time};
const CameraSetting kGain{"Gain (or GainRaw)",
                          "gain_db",
                          "dB",
                          arv_camera_is_gain_available,
                          arv_camera_get_gain_bounds,
                          arv_camera_set_gain,
                          arv_camera_get_gain};

std::string shortNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

// Sets `setting` to `value`; throws naming the feature and the field when the camera has no such
// feature, `value` lies outside its range, or the camera took another value (more than 1 % or
// one unit off: cameras round to their steps).
void setNumber(ArvCamera* c, const CameraSetting& setting, double value) {
  const std::string asked = std::string(" (AravisConfig.") + setting.field + " " +
                            shortNumber(value) + " " + setting.unit + ")";
  Error error;
  if (!setting.available(c, error.out()) || error)
    throw std::runtime_error(std::string("the camera has no ") + setting.feature + asked);
  double min = 0, max = 0;
  setting.bounds(c, &min, &max, error.out());
  if (!error && max > min && (value < min || value > max))
    throw std::runtime_error(std::string("the camera takes ") + setting.feature + " from " +
                             shortNumber(min) + " to " + shortNumber(max) + " " + setting.unit +
                             asked);
  setting.set(c, value, error.out());
  if (error)
    throw std::runtime_error(std::string("the camera refused ") + setting.feature + asked + ": " +
                             error.message());
  const double taken = setting.get(c, error.out());
  if (!error && std::abs(taken - value) > std::max(1.0, 0.01 * std::abs(value)))
    throw std::runtime_error(std::string("the camera set ") + setting.feature + " to " +
                             shortNumber(taken) + " " + setting.unit + " when asked" + asked);
}

std::string formatName(ArvPixelFormat format) {
  switch (format) {
    case ARV_PIXEL_FORMAT_MONO_8:
      return "Mono8";
    case ARV_PIXEL_FORMAT_MONO_10:
      return "Mono10";
    case ARV_PIXEL_FORMAT_MONO_12:
      return "Mono12";
    case ARV_PIXEL_FORMAT_MONO_16:
      return "Mono16";
    case ARV_PIXEL_FORMAT_BAYER_RG_8:
      return "BayerRG8";
    case ARV_PIXEL_FORMAT_RGB_8_PACKED:
      return "RGB8";
    default:
      break;
  }
  char text[32];
  std::snprintf(text, sizeof text, "pixel format 0x%08x", static_cast<unsigned>(format));
  return text;
}

std::string sizeText(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// Pixel format and region, as asked; throws naming what was asked when the camera refuses.
void setFormatAndRegion(ArvCamera* c, const AravisConfig& config) {
  Error error;
  arv_camera_set_pixel_format(c, asked(config.pixel_format), error.out());
  if (error)
    throw std::runtime_error("the camera does not take pixel format " +
                             formatName(asked(config.pixel_format)) + ": " + error.message());
  if (config.roi_width > 0 && config.roi_height > 0) {
    arv_camera_set_region(c, config.roi_x, config.roi_y, config.roi_width, config.roi_height,
                          error.out());
    if (error)
      throw std::runtime_error("the camera refuses the " +
                               sizeText(config.roi_width, config.roi_height) + " region at (" +
                               std::to_string(config.roi_x) + ", " + std::to_string(config.roi_y) +
                               "): " + error.message());
  }
}

// The shape the camera took; throws naming both when it is not the one asked. Cameras that
// check nothing take a region beyond their sensor and pad it: the sensor is checked too.
FrameShape takenShape(ArvCamera* c, const AravisConfig& config) {
  Error error;
  FrameShape shape;
  int x = 0, y = 0, sensor_width = 0, sensor_height = 0;
  arv_camera_get_region(c, &x, &y, &shape.width, &shape.height, error.out());
  error.check("the camera's region");
  shape.format = arv_camera_get_pixel_format(c, error.out());
  error.check("the camera's pixel format");
  arv_camera_get_sensor_size(c, &sensor_width, &sensor_height, error.out());
  const bool sensor_known = !error && sensor_width > 0 && sensor_height > 0;
  const FrameShape wanted{config.roi_width, config.roi_height, asked(config.pixel_format)};
  if (shape.format != wanted.format)
    throw std::runtime_error("the camera took " + formatName(shape.format) + " when asked for " +
                             formatName(wanted.format) + " (AravisConfig.pixel_format)");
  if (config.roi_width == 0 || config.roi_height == 0) return shape;
  if (sensor_known && (config.roi_x + config.roi_width > sensor_width ||
                       config.roi_y + config.roi_height > sensor_height))
    throw std::runtime_error("the camera has a " + sizeText(sensor_width, sensor_height) +
                             " sensor: it cannot send the " + describe(wanted) +
                             " frames asked (AravisConfig.roi_*, the calibration's image size)");
  if (shape.width != wanted.width || shape.height != wanted.height || x != config.roi_x ||
      y != config.roi_y)
    throw std::runtime_error("the camera took a " + sizeText(shape.width, shape.height) +
                             " region at (" + std::to_string(x) + ", " + std::to_string(y) +
                             ") when asked for " + sizeText(wanted.width, wanted.height) + " at (" +
                             std::to_string(config.roi_x) + ", " + std::to_string(config.roi_y) +
                             ")");
  return shape;
}

}  // namespace

std::string describe(const FrameShape& shape) {
  return sizeText(shape.width, shape.height) + " " + formatName(shape.format);
}

bool isUsb(const std::string& camera) { return camera.rfind("usb3:", 0) == 0; }

GPtr<ArvDevice> openDevice(const std::string& camera) {
  Error error;
  ArvDevice* device = nullptr;
  if (isUsb(camera)) {
    // usb3:VENDOR:MODEL:SERIAL, matched against the local USB devices.
    std::string fields[3];
    std::size_t begin = 5;
    for (int i = 0; i < 3; ++i) {
      const std::size_t end = i < 2 ? camera.find(':', begin) : camera.size();
      if (end == std::string::npos)
        throw std::invalid_argument("AravisConfig.camera '" + camera +
                                    "' must be usb3:VENDOR:MODEL:SERIAL");
      fields[i] = camera.substr(begin, end - begin);
      begin = end + 1;
    }
    device =
        arv_uv_device_new(fields[0].c_str(), fields[1].c_str(), fields[2].c_str(), error.out());
  } else {
    GPtr<GInetAddress> device_address(g_inet_address_new_from_string(camera.c_str()));
    if (!device_address)
      throw std::invalid_argument("AravisConfig.camera '" + camera + "' is not an IPv4 address");
    GPtr<GInetAddress> interface_address(
        g_inet_address_new_from_string(localAddressFor(camera).c_str()));
    device = arv_gv_device_new(interface_address.get(), device_address.get(), error.out());
  }
  GPtr<ArvDevice> owned(device);
  error.check("cannot open camera " + camera);
  if (!owned) throw std::runtime_error("cannot open camera " + camera);
  return owned;
}

// SFNC's PtpEnable or the older GevIEEE1588 on, and its status (PtpStatus, GevIEEE1588Status)
// Master or Slave where it has one.
bool ptpSynchronized(ArvDevice* device) {
  const std::pair<const char*, const char*> features[] = {{"PtpEnable", "PtpStatus"},
                                                          {"GevIEEE1588", "GevIEEE1588Status"}};
  for (const auto& [enable, status] : features) {
    if (arv_device_get_feature(device, enable) == nullptr) continue;
    Error error;
    const bool on = arv_device_get_boolean_feature_value(device, enable, error.out());
    if (error || !on) continue;
    if (arv_device_get_feature(device, status) == nullptr) return true;
    const char* state = arv_device_get_string_feature_value(device, status, error.out());
    const std::string s = error || state == nullptr ? "" : state;
    if (s == "Master" || s == "Slave") return true;
  }
  return false;
}

void checkCameraId(ArvCamera* c, const AravisConfig& config) {
  if (config.camera_id.empty()) return;
  Error error;
  const char* serial = arv_camera_get_device_serial_number(c, error.out());
  const std::string serial_text = error || serial == nullptr ? "" : serial;
  const char* id = arv_camera_get_device_id(c, error.out());
  const std::string id_text = error || id == nullptr ? "" : id;
  if (config.camera_id == serial_text || config.camera_id == id_text) return;
  const std::string seen = !serial_text.empty() ? serial_text : id_text;
  throw std::runtime_error("the camera is '" + seen + "', not the camera '" + config.camera_id +
                           "' the calibration was taken with (its camera_id)");
}

FrameShape configureCamera(ArvCamera* c, const AravisConfig& config) {
  Error error;
  arv_camera_stop_acquisition(c, error.out());  // settings may be locked while acquiring
  arv_camera_set_acquisition_mode(c, ARV_ACQUISITION_MODE_CONTINUOUS, error.out());
  error.check("AcquisitionMode");
  setFormatAndRegion(c, config);
  if (config.exposure_us > 0) setNumber(c, kExposure, config.exposure_us);
  if (config.gain_db >= 0) setNumber(c, kGain, config.gain_db);
  if (config.trigger == TriggerMode::FreeRunning) {
    if (config.frame_rate > 0) {
      arv_camera_set_frame_rate(c, config.frame_rate, error.out());
      error.check("AcquisitionFrameRate");
    }
    arv_camera_clear_triggers(c, error.out());  // not every camera has triggers
  } else {
    arv_camera_set_trigger(c, "Software", error.out());
    error.check("software trigger");
  }
  if (arv_camera_is_gv_device(c) && config.packet_size > 0) {
    arv_camera_gv_set_packet_size(c, config.packet_size, error.out());
    error.check("GevSCPSPacketSize");
  }
  return takenShape(c, config);
}

}  // namespace multislit::aravis
