// multislit record: what a live camera sends, saved as a recording that `map --sequence`,
// `detect` and a bug report read: PNG frames (8-bit for Mono8, 16-bit for Mono12 and Mono16),
// frames.csv (each frame's file, stamp and the clock of the stamp), sensor.yaml and, with
// --calibration, calibration.yaml. Every file is written whole (a temporary file renamed into
// place), frames.csv a whole row after each frame: it always lists the frames on disk.
#include "camera_options.h"
#include "cli.h"
#include "commands.h"
#include "common.h"
#include "config_options.h"
#include "output_file.h"
#include "recording.h"

#include "multislit/sources.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>

namespace multislit::apps {
namespace {

/// Nothing from the camera for this long, not even after reopening it: the recording ends with an
/// error (its files whole). [s]
constexpr double kRecordSilenceS = 10.0;

void declareRecordOptions(cli::ArgParser& args) {
  args.option("camera", "", "GigE Vision camera address (127.0.0.1 for multislit emulate)");
  args.option("out", "", "folder of the recording (created; must not hold a recording yet)");
  args.option("frames", "0", "stop after this many frames (0: no limit)");
  args.option("seconds", "0", "stop after this long [s] (0: no limit); not with --frames");
  args.option("fps", defaultText(AravisConfig{}.frame_rate), "camera frame rate [Hz]");
  args.option("calibration", "",
              "calibration YAML of multislit calibrate: the camera sends its image size and must "
              "be its camera_id; copied into the recording (default: the sensor's image size)");
  args.option("sensor", "",
              "sensor YAML written as the recording's sensor.yaml (default: the paper's sensor)");
  addCameraOptions(args);
}

/// The camera as the options ask: region and identity from the calibration, else the sensor's
/// image size.
AravisConfig recordCamera(const cli::ArgParser& args, const std::optional<Reference>& reference,
                          const SensorConfig& sensor) {
  AravisConfig config = cameraSettingsFromArgs(args);
  config.camera = args.str("camera");
  config.frame_rate = args.number("fps", 0.1, 1000);
  config.roi_width = reference ? reference->image_width : sensor.camera.width;
  config.roi_height = reference ? reference->image_height : sensor.camera.height;
  if (reference) config.camera_id = reference->camera_id;
  validateOptions(config, args, {{"frame_rate", "fps"}});
  return config;
}

const char* clockColumn(StampSource source) {
  return source == StampSource::Camera ? "camera" : "host";
}

/// Frames on stderr: a status line on a terminal at most twice a second, else a line every 5 s;
/// `last_line` at the end.
void recordProgress(std::size_t frames, double seconds, const SourceStats& stats,
                    bool last_line = false) {
  static double last = -1e9;
  const bool terminal = isatty(STDERR_FILENO) != 0;
  if (!last_line && seconds - last < (terminal ? 0.5 : 5.0)) return;
  last = seconds;
  std::fprintf(stderr, "%srecord: %zu frames in %.1f s (%.1f fps), %llu camera buffers skipped%s",
               terminal ? "\r" : "", frames, seconds,
               static_cast<double>(frames) / std::max(seconds, 1e-9),
               static_cast<unsigned long long>(stats.bad_buffers), terminal ? "   " : "\n");
}

/// What the recording loop saw.
struct RecordCounts {
  StampSource clock = StampSource::Host;  ///< the stamps' clock, of the last frame
  double seconds = 0.0;                   ///< from the start of the camera [s]
  std::string silence;                    ///< why the camera stopped sending; "" when it did not
};

/// Frames of the started `source` into `recording` until `max_frames` (0: no limit), `max_seconds`
/// (0: no limit), Ctrl-C, or a camera silent for kRecordSilenceS.
RecordCounts recordFrames(AravisSource& source, SequenceRecorder& recording, long max_frames,
                          double max_seconds) {
  RecordCounts n;
  const auto t0 = std::chrono::steady_clock::now();
  auto last_frame = t0;
  const auto since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  while (!StopSignal::requested() &&
         (max_frames == 0 || static_cast<long>(recording.frames()) < max_frames) &&
         (max_seconds == 0 || since(t0) < max_seconds)) {
    const std::optional<Frame> frame = source.next(std::chrono::milliseconds(200));
    n.seconds = since(t0);
    if (!frame) {
      if (since(last_frame) < kRecordSilenceS) continue;
      const std::string why = source.lastError();
      n.silence = "no frame from " + source.name() + " for " + defaultText(kRecordSilenceS) + " s" +
                  (why.empty() ? "" : ": " + why);
      break;
    }
    last_frame = std::chrono::steady_clock::now();
    recording.add(frame->image, frame->stamp_us, clockColumn(frame->stamp_source));
    n.clock = frame->stamp_source;
    recordProgress(recording.frames(), n.seconds, source.stats());
  }
  recordProgress(recording.frames(), n.seconds, source.stats(), true);
  return n;
}

}  // namespace

int runRecord(int argc, char** argv) {
  cli::ArgParser args(
      "record",
      "Saves what a live camera sends as a recording that map --sequence and detect read:\n"
      "PNG frames (8-bit for Mono8, 16-bit for Mono12 and Mono16), frames.csv (each frame's\n"
      "file, stamp_us and the clock of the stamp: camera or host), sensor.yaml and, with\n"
      "--calibration, calibration.yaml, each written whole; frames.csv grows a row after each\n"
      "frame, so it lists the frames on disk however the recording ends. Ctrl-C ends it at a\n"
      "frame boundary. Replay it with\n"
      "  multislit map --sequence DIR --calibration DIR/calibration.yaml --out out/map\n"
      "Example: multislit record --camera 192.168.1.20 --calibration calib.yaml \\\n"
      "             --sensor sensor.yaml --seconds 60 --exposure 2000 --out run1");
  declareRecordOptions(args);
  if (!args.parse(argc, argv)) return 0;
  if (!args.has("camera")) throw cli::UsageError("--camera ADDR is needed");
  if (!args.has("out")) throw cli::UsageError("--out DIR is needed");
  const long max_frames = args.integer("frames", 0, 1000000000);
  const double max_seconds = args.number("seconds", 0, 1e9);
  if (max_frames > 0 && max_seconds > 0)
    throw cli::UsageError("give --frames or --seconds, not both");
  const std::filesystem::path out = args.str("out");
  if (std::filesystem::exists(out / "frames.csv"))
    throw cli::UsageError("--out " + out.string() +
                          " already holds a recording (frames.csv): give another folder");
  std::optional<Reference> reference;
  if (args.has("calibration")) reference = Reference::load(args.str("calibration"));
  const SensorConfig sensor =
      args.has("sensor") ? SensorConfig::load(args.str("sensor")) : SensorConfig{};
  AravisSource source(recordCamera(args, reference, sensor));

  const StopSignal stop;  // Ctrl-C and SIGTERM end the recording at a frame boundary
  source.start();         // a camera that cannot be opened leaves no file behind
  SequenceRecorder recording(out, "--out", reference ? &*reference : nullptr, sensor,
                             inputsOf(args, {"calibration", "sensor"}));
  const RecordCounts counts = recordFrames(source, recording, max_frames, max_seconds);
  source.stop();
  recording.finish();
  if (isatty(STDERR_FILENO)) std::fprintf(stderr, "\n");
  const SourceStats stats = source.stats();
  std::cout << "recorded " << recording.frames() << " frames of " << source.name() << " in "
            << defaultText(counts.seconds) << " s into " << out.string() << " (stamps: "
            << (recording.frames() > 0
                    ? timeBaseText(counts.clock, source.config().ptp_utc_offset_s)
                    : std::string("none"))
            << "; " << stats.bad_buffers << " camera buffers skipped, " << stats.losses
            << " losses)" << (StopSignal::requested() ? " (interrupted)" : "") << "\n";
  if (!counts.silence.empty()) throw std::runtime_error(counts.silence);
  return StopSignal::requested() ? kInterruptedExit : 0;
}

}  // namespace multislit::apps
