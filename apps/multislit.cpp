// multislit: the command-line front end. Each subcommand lives in its own cmd_*.cpp.
#include "cli.h"
#include "commands.h"

#include <cstring>
#include <exception>
#include <iostream>

namespace {

struct Command {
  const char* name;
  const char* summary;
  int (*run)(int argc, char** argv);
};

const Command kCommands[] = {
    {"walk", "the paper's walking experiment: a simulated HOAP-2 avoids a ball and a cable",
     multislit::apps::runWalk},
    {"map",
     "the whole chain on a camera, a recording or the simulator, with odometry: map, decisions",
     multislit::apps::runMap},
    {"record", "save what a live camera sends (frames, stamps, sensor) for map --sequence",
     multislit::apps::runRecord},
    {"simulate", "render reference and sequence images of a simulated scene, with ground truth",
     multislit::apps::runSimulate},
    {"emulate", "serve the simulator's images of a walk as a GigE Vision camera on 127.0.0.1",
     multislit::apps::runEmulate},
    {"calibrate", "find the slits in a reference image and store regions and metric scale",
     multislit::apps::runCalibrate},
    {"rdmap", "measure the relative disparity map of images, written as PCD clouds",
     multislit::apps::runRdmap},
    {"detect", "find the floor and the obstacles in frames, one JSON line per frame",
     multislit::apps::runDetect},
    {"table1", "reproduce Table I and Fig. 12: floor residual std at the seven poses",
     multislit::apps::runTable1},
    {"bench", "time every stage on one core against the stock PCL path", multislit::apps::runBench},
};

void printUsage(std::ostream& out) {
  out << "usage: multislit <command> [options]   (multislit <command> --help for its options)\n"
      << "       multislit --version\n\n"
      << "commands:\n";
  for (const Command& c : kCommands)
    out << "  " << c.name << std::string(12 - std::strlen(c.name), ' ') << c.summary << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[1], "--version") == 0) {
    std::cout << "multislit " << MULTISLIT_VERSION << "\n";
    return 0;
  }
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0) {
    printUsage(argc < 2 ? std::cerr : std::cout);
    return argc < 2 ? 2 : 0;
  }
  for (const Command& c : kCommands) {
    if (std::strcmp(argv[1], c.name) != 0) continue;
    try {
      return c.run(argc - 2, argv + 2);
    } catch (const multislit::cli::UsageError& e) {
      std::cerr << "multislit " << c.name << ": " << e.what() << " (see multislit " << c.name
                << " --help)\n";
      return 2;
    } catch (const std::exception& e) {
      std::cerr << "multislit " << c.name << ": error: " << e.what() << "\n";
      return 1;
    }
  }
  std::cerr << "multislit: unknown command '" << argv[1] << "'\n";
  printUsage(std::cerr);
  return 2;
}
