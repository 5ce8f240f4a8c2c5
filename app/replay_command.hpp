// `pamdp replay`: one replay shard of the distributed system (docs/protocol.md). The shard's
// settings come from the experiment config the learner hands out in its ClusterMap; these
// functions are that mapping, kept here so that replay/ knows nothing of TOML or envs.
#pragma once

#include <string>

#include "app/experiment_config.hpp"
#include "replay/shard_server.hpp"

namespace pamdp::app {

// replay.capacity / replay.shards transitions; widths of the env config.env names (it is
// constructed once to ask); samples per insert = cluster.samples_per_insert, or
// train.updates_per_step * ddpg.batch_size when that is 0; min_size = replay.warmup /
// replay.shards; slack = cluster.rate_limit_slack. Throws std::runtime_error naming the key if
// the config cannot describe a shard (capacity below one transition per shard).
ShardConfig shard_config_from_experiment(const ExperimentConfig& config);
// Parses a ClusterMap's config_toml and maps it: the ShardServer's ShardConfigFromMap.
ShardConfig shard_config_from_toml(const std::string& config_toml);

}  // namespace pamdp::app
