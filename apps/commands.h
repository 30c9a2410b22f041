// rtlab — subcommands of the rtlab executable. Each add* registers its flags on the app; run()
// dispatches to the one that was parsed.
#pragma once

#include <CLI/CLI.hpp>

namespace rt::cli {

void addRender(CLI::App& app);
void addDevices(CLI::App& app);
void addCompare(CLI::App& app);  // apps/compare.cpp
bool compareParsed();
int runCompare();
void addSweep(CLI::App& app);  // apps/sweep.cpp
int run(CLI::App& app);
int runSweepCommand();           // apps/sweep.cpp
void addLists(CLI::App& app);    // apps/list.cpp: rtlab scenes, rtlab sweeps
int runLists();                  // -1 when neither was parsed
void addPredict(CLI::App& app);  // apps/predict.cpp: rtlab predict
bool predictParsed();
int runPredict();

}  // namespace rt::cli
