// The experiment config parser (`--config FILE`, a run directory's config.toml, the config a
// shard and an actor get in the learner's ClusterMap): parse_experiment_config on fuzzed TOML,
// and the same text's lines as `--set key=value` overrides on the defaults. Refusals are
// exceptions naming the key and the valid choices; anything else is a finding. Valid configs are
// written back with to_toml and must parse again to the same text.
#include <cstddef>
#include <cstdint>
#include <exception>
#include <sstream>
#include <string>
#include <vector>

#include "app/experiment_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const pamdp::app::ExperimentConfig c = pamdp::app::parse_experiment_config(text, "fuzz.toml", {});
    const std::string again = pamdp::app::to_toml(c);
    if (pamdp::app::to_toml(pamdp::app::parse_experiment_config(again, "to_toml", {})) != again) {
      __builtin_trap();  // a config we wrote must read back the same
    }
  } catch (const std::exception&) {
  }
  std::vector<std::string> overrides;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line) && overrides.size() < 16;) {
    overrides.push_back(line);
  }
  try {
    (void)pamdp::app::parse_experiment_config("", "defaults", overrides);
  } catch (const std::exception&) {
  }
  return 0;
}
