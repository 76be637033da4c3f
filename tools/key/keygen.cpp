// stride-keygen: a new shared secret key for signed messages (messages/README.md, "Signing").
//   stride-keygen FILE
// Writes 32 random bytes to FILE as 64 hex digits and a newline, readable and writable by its
// owner only (0600), and prints the key's id (the id receivers name when a message was signed with
// another key). An existing file is never overwritten.
// Exit status: 0 written; 1 the file exists or cannot be written; 2 bad arguments.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <stdexcept>
#include <string>

#include "config/command_line.hpp"
#include "messages/signing.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "stride-keygen: a new secret key for signed Stride messages, written to FILE (mode 0600, "
      "never over an existing file)"};
  stride::commandLineConventions(app, "stride-keygen");
  std::string path;
  app.add_option("FILE", path, "the key file to create")->required();
  if (const int status = stride::parseCommandLine(app, argc, argv); status >= 0) return status;

  try {
    stride::msg::writeNewKeyFile(path);
    // Read back as every program will: the file is a key they accept.
    const stride::msg::Key key = stride::msg::loadKeyFile(path);
    std::printf("stride-keygen: wrote a new key to %s (key id %08x)\n", path.c_str(),
                static_cast<unsigned>(key.id));
  } catch (const std::runtime_error& e) {
    std::fprintf(stderr, "stride-keygen: %s\n", e.what());
    return 1;
  }
  return 0;
}
