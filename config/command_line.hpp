#pragma once
// The command-line conventions every Stride program keeps: `--version`, the defaults shown in
// `--help`, and a usage error that exits 2 with the usage line (CLI11's own exit codes, 100 and
// up, would tell a script nothing it could rely on). Programs link `stride_command_line`, which
// defines STRIDE_VERSION from the CMake project's version.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>

#ifndef STRIDE_VERSION
#error "STRIDE_VERSION is not defined: link the program to stride_command_line (config/)"
#endif

namespace stride {

// Call right after constructing the app, before adding options (the defaults apply to options
// added afterwards).
inline void commandLineConventions(CLI::App& app, const std::string& program) {
  app.name(program);
  app.option_defaults()->always_capture_default();
  app.set_version_flag("--version", program + " " + STRIDE_VERSION);
}

// Parses the command line. Returns -1 when the program is to run on, otherwise the status to exit
// with: 0 after --help or --version (printed), 2 after a usage error (the error and the usage line
// on stderr).
inline int parseCommandLine(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
    return -1;
  } catch (const CLI::ParseError& e) {
    if (app.exit(e) == 0) return 0;  // --help, --version: CLI11 printed them
    std::fprintf(stderr, "%s", CLI::Formatter().make_usage(&app, app.get_name()).c_str());
    return 2;
  }
}

}  // namespace stride
