// Writes the fuzzers' seed corpora from valid inputs: one file per protocol message (built with
// core/wire's builders), a checkpoint of the toy task's learner, a replay snapshot, and
// TransitionBatch recipes. tests/fuzz.sh adds deploy/configs/*.toml for fuzz_config.
// Usage: fuzz_seeds OUT_DIR  (creates OUT_DIR/<target>/...)
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "core/files.hpp"
#include "core/wire.hpp"
#include "envs/toy/reach_stop.hpp"
#include "learner/checkpoint.hpp"
#include "learner/ddpg_algorithm.hpp"
#include "replay/replay_snapshot.hpp"

namespace fs = std::filesystem;
using namespace pamdp;

namespace {

void write(const fs::path& path, const uint8_t* data, size_t size) {
  fs::create_directories(path.parent_path());
  write_file_atomically(path.string(), data, size);
}

void write(const fs::path& path, const flatbuffers::FlatBufferBuilder& fbb) {
  write(path, fbb.GetBufferPointer(), fbb.GetSize());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_seeds OUT_DIR\n");
    return 2;
  }
  const fs::path out = argv[1];
  const fs::path env_dir = out / "fuzz_envelope";
  flatbuffers::FlatBufferBuilder fbb;

  const int obs = 3;
  const int act = 4;
  const uint32_t n = 5;
  std::vector<float> states(n * obs, 0.5F), actions(n * act, -0.25F), rewards(n, 1.0F), next(n * obs, 0.75F),
      returns(n, 2.0F);
  std::vector<uint8_t> terminals(n, 0);
  terminals.back() = 1;
  const wire::TransitionRows rows{
      n, obs, act, states.data(), actions.data(), rewards.data(), next.data(), terminals.data(), returns.data()};

  wire::build_join_request(fbb, wire::Role::Shard, "replay@host:1", "tcp://127.0.0.1:4000", "tcp://127.0.0.1:4001", 0,
                           "http://127.0.0.1:9000/metrics");
  write(env_dir / "join_request_shard", fbb);
  wire::build_join_request(fbb, wire::Role::Actor, "host:2", "", "", 2);
  write(env_dir / "join_request_actor", fbb);
  wire::build_cluster_map(fbb, 3, "seed = 1\n[env]\nname = \"reach_stop\"\n", {"tcp://a:1", "tcp://b:2"},
                          {"tcp://a:3", "tcp://b:4"}, "tcp://l:5556", 1, 2, 7);
  write(env_dir / "cluster_map", fbb);
  wire::build_transition_batch(fbb, 1, 42, rows);
  write(env_dir / "transition_batch", fbb);
  wire::build_sample_request(fbb, 9, 32);
  write(env_dir / "sample_request", fbb);
  wire::build_sample_reply(fbb, 9, rows);
  write(env_dir / "sample_reply", fbb);
  const std::vector<int> widths = {3, 8, 4};
  std::vector<float> params(3 * 8 + 8 + 8 * 4 + 4, 0.1F);
  const NetworkView actor{"actor", widths, params};
  wire::build_policy_weights(fbb, 4, 1000, "ddpg", 0, {&actor, 1});
  write(env_dir / "policy_weights", fbb);
  wire::build_episode_report(fbb, 1, 10, 0.5F, 20, 1, 4);
  write(env_dir / "episode_report", fbb);
  const std::vector<int64_t> counters = {1, 2, 3, 4, 5, 6};
  wire::build_heartbeat(fbb, wire::Role::Shard, "replay@host:1", 3, counters);
  write(env_dir / "heartbeat", fbb);
  wire::build_metrics_urls_request(fbb);
  write(env_dir / "metrics_urls_request", fbb);
  wire::build_metrics_urls(fbb, {"http://127.0.0.1:9000/metrics", "http://127.0.0.1:9001/metrics"});
  write(env_dir / "metrics_urls", fbb);
  wire::build_insert_ack(fbb, 42, 64);
  write(env_dir / "insert_ack", fbb);

  // fuzz_transition_batch reads: obs, act (u8), count (u16), expect flags, max_count (u16), then
  // per-array length choices and floats. A consistent batch of 5 rows of widths 3/4:
  const std::vector<uint8_t> consistent = {3, 4, 5, 0, 1, 1, 0, 2, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0x3f, 0, 0, 0x40};
  write(out / "fuzz_transition_batch" / "consistent", consistent.data(), consistent.size());
  const std::vector<uint8_t> short_actions = {3, 4, 5, 0, 1, 1, 0, 2, 1, 0x14, 1, 1, 1, 1, 0, 0, 0x80, 0x7f, 0xff};
  write(out / "fuzz_transition_batch" / "short_actions", short_actions.data(), short_actions.size());

  // A checkpoint of the toy task's learner with hidden widths 8, 8 (fuzz_checkpoint's shape).
  toy::ReachStopEnv env;
  DdpgConfig config;
  config.hidden = {8, 8};
  DdpgAlgorithm ddpg(env.observation_size(), env.action_space(), config, 1, UpdateDevice::kCpu);
  CheckpointMeta meta;
  meta.config_toml = "seed = 1\n[env]\nname = \"reach_stop\"\n[ddpg]\nhidden = [8, 8]\n";
  meta.env_steps = 100;
  meta.episodes = 3;
  meta.rng_states = {{1, 2, 3, 4}};
  fs::create_directories(out / "fuzz_checkpoint");
  save_checkpoint((out / "fuzz_checkpoint" / "toy.ckpt").string(), ddpg, meta);

  // A replay snapshot of capacity 64, widths 3/4 (fuzz_replay_snapshot's shape), 10 rows.
  ReplayBuffer buffer(64, obs, act);
  for (int i = 0; i < 10; ++i) {
    buffer.insert({std::span<const float>(states.data(), obs), std::span<const float>(actions.data(), act), 1.0F,
                   std::span<const float>(next.data(), obs), i == 9, 0.5F});
  }
  fs::create_directories(out / "fuzz_replay_snapshot");
  save_replay_snapshot((out / "fuzz_replay_snapshot" / "ten_rows.replay").string(), buffer);
  ReplayBuffer empty(64, obs, act);
  save_replay_snapshot((out / "fuzz_replay_snapshot" / "empty.replay").string(), empty);
  std::printf("fuzz_seeds: wrote seeds under %s\n", out.c_str());
  return 0;
}
