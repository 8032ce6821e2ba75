// Entry points of the multislit subcommands; argv holds only the command's own arguments.
#pragma once

namespace multislit::apps {

/// The demo's walk: multislit walk's frames (30 Hz; the paper's run is about as long).
constexpr long kWalkFrames = 900;

int runSimulate(int argc, char** argv);
int runWalk(int argc, char** argv);
int runEmulate(int argc, char** argv);
int runCalibrate(int argc, char** argv);
int runRdmap(int argc, char** argv);
int runDetect(int argc, char** argv);
int runTable1(int argc, char** argv);
int runBench(int argc, char** argv);
int runMap(int argc, char** argv);
int runRecord(int argc, char** argv);

}  // namespace multislit::apps
