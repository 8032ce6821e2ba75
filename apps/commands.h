// Entry points of the multislit subcommands; argv holds only the command's own arguments.
#pragma once

namespace multislit::apps {

int runSimulate(int argc, char** argv);
int runWalk(int argc, char** argv);
int runEmulate(int argc, char** argv);
int runCalibrate(int argc, char** argv);
int runRdmap(int argc, char** argv);
int runDetect(int argc, char** argv);
int runTable1(int argc, char** argv);
int runBench(int argc, char** argv);
int runMap(int argc, char** argv);

}  // namespace multislit::apps
