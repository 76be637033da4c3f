#pragma once
// The command-line conventions every Stride program keeps: `--version`, the defaults shown in
// `--help`, and a usage error that exits 2 with the usage line (CLI11's own exit codes, 100 and
// up, would tell a script nothing it could rely on). Programs link `stride_command_line`, which
// defines STRIDE_VERSION from the CMake project's version.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
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

// The LCM URL a program opens: the one given (a flag, a YAML key), else LCM_DEFAULT_URL, else
// empty. Empty must stop the program (noLcmUrl): LCM's own default is multicast on the host
// network, where nothing of ours may send by accident (LCM-NOTES.md).
inline std::string lcmUrl(const std::string& given) {
  if (!given.empty()) return given;
  const char* env = std::getenv("LCM_DEFAULT_URL");
  return env != nullptr ? env : "";
}

// Says on stderr that no URL was given, and how to give one (`how`: the program's own ways, e.g.
// "pass --url"); returns the usage-error status, 2.
inline int noLcmUrl(const std::string& program, const std::string& how) {
  std::fprintf(stderr,
               "%s: no LCM URL: %s or set LCM_DEFAULT_URL (e.g. udpm://239.255.76.67:7667?ttl=0)\n",
               program.c_str(), how.c_str());
  return 2;
}

}  // namespace stride
