// pmg_keygen: writes a fresh MAC key for the authenticated LCM command channels
// (docs/teleop.md): 32 random bytes (libsodium randombytes) as 64 hex characters, in a
// new file with mode 0600. Never overwrites: an existing file (or link) is an error.
//
//   pmg_keygen --out ~/.config/pmg/commands.key
//
// Then copy it to every commander host and the robot (scp -p keeps the mode), and set
// `security.key_file` in the controller config and `--key` on the commanders.
#include <cstdio>
#include <exception>
#include <string>

#include <CLI/CLI.hpp>

#include "pmg/comms/auth.hpp"

int main(int argc, char** argv) {
  CLI::App app{"pmg_keygen: write a new key for the authenticated LCM command channels (mode 0600)"};
  std::string out;
  app.add_option("--out", out, "key file to create (must not exist)")->required();
  CLI11_PARSE(app, argc, argv);
  try {
    const pmg::comms::AuthKey key = pmg::comms::generateAuthKey();
    pmg::comms::writeAuthKeyFile(out, key);
    std::printf("wrote %s (mode 0600, key id %s)\n", out.c_str(), pmg::comms::keyId(key).c_str());
    std::printf("copy it to the robot and the commander hosts with: scp -p %s HOST:PATH\n", out.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_keygen: %s\n", e.what());
    return 1;
  }
}
