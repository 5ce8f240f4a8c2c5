// `pamdp keygen`: writes the CURVE keys of a cluster (core/transport.hpp, CurveKeyring).
#include <cstdio>
#include <memory>
#include <string>

#include "app/commands.hpp"
#include "core/transport.hpp"

namespace pamdp::app {

void register_keygen(CLI::App& app) {
  auto dir = std::make_shared<std::string>("keys");
  CLI::App* cmd =
      app.add_subcommand("keygen", "write CURVE keys for encrypted, authenticated clusters (server.keys, client.keys)");
  cmd->add_option("--dir", *dir, "directory to write (never overwrites existing keys)")->capture_default_str();
  cmd->callback([dir] {
    net::write_curve_keyring(*dir);
    std::printf(
        "wrote %s/server.keys and %s/client.keys (mode 0600)\n"
        "  learner and replay shards need both files, actors only client.keys; copy them to every machine.\n"
        "  learner: --set cluster.curve=true --set cluster.curve_keys_dir=%s\n"
        "  replay:  --curve-keys %s        actor: --curve-keys %s\n",
        dir->c_str(), dir->c_str(), dir->c_str(), dir->c_str(), dir->c_str());
  });
}

}  // namespace pamdp::app
