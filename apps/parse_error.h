// rtlab — how every front end reports a bad command line: one line naming the flag, the nearest
// flag the command does know (for a typo), the command's --help, and exit status 1.
#pragma once

#include <CLI/CLI.hpp>

namespace rt::cli {

// Exit status of every usage error (bad flag, bad value, unknown command), as the README says.
constexpr int kUsageError = 1;

// Prints `prog: <reason> [(did you mean --x?)] (see <prog [sub]> --help)` on stderr and returns
// kUsageError; for --help (exit code 0) prints the help and returns 0.
int reportParseError(const CLI::App& app, const CLI::ParseError& error, const char* prog, int argc,
                     char** argv);

}  // namespace rt::cli
