// The algorithm seam (learner/algorithm.hpp): the registry, and checkpoints of named tensors,
// through DDPG and through a stand-in algorithm with state of another shape, so that nothing in
// the checkpoint path can lean on DDPG's.
#include "learner/algorithm.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "envs/hfo/hfo_env.hpp"
#include "envs/toy/reach_stop.hpp"
#include "learner/checkpoint.hpp"
#include "learner/ddpg_algorithm.hpp"

namespace pamdp {
namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("pamdp-algorithm-" + name + "-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

DdpgConfig tiny_config() {
  DdpgConfig c;
  c.hidden = {8};
  c.batch_size = 4;
  return c;
}

// State of another shape than DDPG's: one network, one plain tensor, one optional tensor and a
// counter. It neither acts nor learns; it records what the checkpoint path told it.
class StandIn final : public Algorithm {
 public:
  explicit StandIn(bool wants_extra = false) : wants_extra_(wants_extra) {}
  [[nodiscard]] std::string_view name() const override { return "stand-in"; }
  [[nodiscard]] int obs_dim() const override { return 3; }
  [[nodiscard]] int output_width() const override { return 2; }
  [[nodiscard]] int batch_size() const override { return 1; }
  [[nodiscard]] int64_t updates() const override { return updates_; }
  [[nodiscard]] const char* device() const override { return "cpu"; }
  UpdateStats update(const BatchView& /*batch*/, const BatchView* /*demos*/) override { return {}; }
  UpdateStats finish() override { return {}; }
  void sync_acting() override {}
  void act(std::span<const float> /*obs*/, std::span<float> out, ActorCopy /*copy*/) override {
    std::fill(out.begin(), out.end(), 0.0F);
  }
  ActingWeights acting_weights() override { return {name(), 0, {{"q", widths_, net_}}}; }
  void sync_to_host() override { ++syncs; }
  std::vector<StateTensor> state_tensors() override {
    std::vector<StateTensor> t = {{"q", net_, widths_, false}, {"scale", scale_, {}, false}};
    t.push_back({"average", average_, {}, true});
    if (wants_extra_) {
      t.push_back({"extra", extra_, {}, false});
    }
    return t;
  }
  std::vector<StateCounter> state_counters() override { return {{"updates", &updates_}}; }
  void restored(const std::vector<std::string>& missing) override { missing_ = missing; }
  void warm_started() override {}

  std::vector<int> widths_ = {3, 2};
  std::vector<float> net_ = std::vector<float>(3 * 2 + 2, 0.0F);
  std::vector<float> scale_ = {0.0F, 0.0F};
  std::vector<float> average_ = {0.0F};
  std::vector<float> extra_ = {0.0F};
  int64_t updates_ = 0;
  std::vector<std::string> missing_ = {"not told"};
  int syncs = 0;

 private:
  bool wants_extra_;
};

TEST(Algorithm, TheRegistryMakesDdpgAndNamesWhatItHas) {
  toy::ReachStopEnv env;
  const DdpgConfig config = tiny_config();
  AlgorithmArgs args;
  args.obs_dim = env.observation_size();
  args.space = &env.action_space();
  args.ddpg = &config;
  args.seed = 1;
  args.device = UpdateDevice::kCpu;
  const std::unique_ptr<Algorithm> a = make_algorithm("ddpg", args);
  EXPECT_EQ(a->name(), "ddpg");
  EXPECT_EQ(a->output_width(), env.action_space().output_width());
  EXPECT_STREQ(a->device(), "cpu");
  ASSERT_NE(algorithm_registry().find("ddpg"), nullptr);
  try {
    (void)make_algorithm("p-dqn-typo", args);
    FAIL() << "an unknown algorithm was made";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("p-dqn-typo"), std::string::npos) << what;
    EXPECT_NE(what.find("train.algorithm"), std::string::npos) << what;
    EXPECT_NE(what.find("ddpg"), std::string::npos) << what;
  }
}

// A checkpoint holds whatever tensors and counters the algorithm names, and gives them back; an
// optional tensor the file lacks is reported as missing, a required one refuses the file.
TEST(Checkpoint, HoldsAnyAlgorithmsNamedTensors) {
  const fs::path dir = fresh_dir("named");
  const std::string path = (dir / "s.ckpt").string();
  StandIn from;
  for (size_t i = 0; i < from.net_.size(); ++i) {
    from.net_[i] = 0.5F * static_cast<float>(i);
  }
  from.scale_ = {2.0F, -3.0F};
  from.average_ = {7.0F};
  from.updates_ = 41;
  CheckpointMeta meta;
  meta.episodes = 5;
  save_checkpoint(path, from, meta);
  EXPECT_EQ(from.syncs, 1);  // saving brings the state to the host first
  EXPECT_EQ(read_checkpoint_algorithm(path), "stand-in");

  StandIn back;
  EXPECT_EQ(load_checkpoint(path, back).episodes, 5);
  EXPECT_EQ(back.net_, from.net_);
  EXPECT_EQ(back.scale_, from.scale_);
  EXPECT_EQ(back.average_, from.average_);
  EXPECT_EQ(back.updates_, 41);
  EXPECT_TRUE(back.missing_.empty());

  StandIn wants_more(/*wants_extra=*/true);
  try {
    load_checkpoint(path, wants_more);
    FAIL() << "a checkpoint without a required tensor was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("missing extra"), std::string::npos) << e.what();
  }
  EXPECT_EQ(wants_more.updates_, 0);  // refused before anything was copied
  EXPECT_EQ(wants_more.missing_, std::vector<std::string>{"not told"});
  fs::remove_all(dir);
}

// Another algorithm's checkpoint is refused with the key that picks the algorithm, both ways.
TEST(Checkpoint, AnotherAlgorithmsFileIsRefusedNamingTheKey) {
  const fs::path dir = fresh_dir("other");
  const std::string stand_in = (dir / "s.ckpt").string();
  const std::string ddpg_file = (dir / "d.ckpt").string();
  StandIn s;
  save_checkpoint(stand_in, s, {});
  toy::ReachStopEnv env;
  DdpgAlgorithm d(3, env.action_space(), tiny_config(), 1, UpdateDevice::kCpu);
  save_checkpoint(ddpg_file, d, {});
  const auto refused = [](const std::function<void()>& load, const std::string& written_by) {
    try {
      load();
      ADD_FAILURE() << "another algorithm's checkpoint was accepted";
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("algorithm '" + written_by + "'"), std::string::npos) << what;
      EXPECT_NE(what.find("train.algorithm"), std::string::npos) << what;
    }
  };
  refused([&] { load_checkpoint(stand_in, d); }, "stand-in");
  refused([&] { warm_start_from_checkpoint(stand_in, d); }, "stand-in");
  refused([&] { load_checkpoint(ddpg_file, s); }, "ddpg");
  fs::remove_all(dir);
}

// Checkpoints written before the algorithm seam (schema version 1, DDPG in fixed fields) load as
// DDPG, and written again (version 2, named tensors) hold the same state.
TEST(Checkpoint, VersionOneFilesLoadAsDdpgAndRoundTrip) {
  const std::string model = std::string(PAMDP_SOURCE_DIR) + "/models/hfo-1v0-fast-seed1.ckpt";
  ASSERT_EQ(read_checkpoint_algorithm(model), "ddpg");
  const std::string text = read_checkpoint_config(model);
  ASSERT_NE(text.find("hidden = [ 256, 128, 64 ]"), std::string::npos) << "the model's widths changed";
  const ActionSpace& hfo_space = hfo::hfo_action_space();
  DdpgConfig c;
  c.hidden = {256, 128, 64};  // fast.toml's, as the model's
  DdpgAlgorithm old_format(58, hfo_space, c, 1, UpdateDevice::kCpu);
  const CheckpointMeta meta = load_checkpoint(model, old_format);
  EXPECT_GT(old_format.updates(), 0);

  const fs::path dir = fresh_dir("v1");
  const std::string again = (dir / "v2.ckpt").string();
  save_checkpoint(again, old_format, meta);
  DdpgAlgorithm new_format(58, hfo_space, c, 2, UpdateDevice::kCpu);
  load_checkpoint(again, new_format);
  const std::vector<StateTensor> a = old_format.state_tensors();
  const std::vector<StateTensor> b = new_format.state_tensors();
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_TRUE(std::equal(a[i].values.begin(), a[i].values.end(), b[i].values.begin(), b[i].values.end()))
        << a[i].name;
  }
  std::vector<StateCounter> ca = old_format.state_counters();
  std::vector<StateCounter> cb = new_format.state_counters();
  ASSERT_EQ(ca.size(), cb.size());
  for (size_t i = 0; i < ca.size(); ++i) {
    EXPECT_EQ(*ca[i].value, *cb[i].value) << ca[i].name;
  }
  fs::remove_all(dir);
}

// What the actors are sent: the algorithm's name and its acting networks, from the host copy.
TEST(Algorithm, DdpgPublishesItsActorUnderItsName) {
  toy::ReachStopEnv env;
  DdpgConfig c = tiny_config();
  c.bound = BoundMethod::kSquashing;
  DdpgAlgorithm d(3, env.action_space(), c, 1, UpdateDevice::kCpu);
  const ActingWeights w = d.acting_weights();
  EXPECT_EQ(w.algorithm, "ddpg");
  EXPECT_EQ(w.bound, 2);
  ASSERT_EQ(w.networks.size(), 1U);
  EXPECT_EQ(w.networks[0].name, "actor");
  EXPECT_EQ(w.networks[0].params.data(), d.ddpg().actor().params().data());
  EXPECT_TRUE(std::equal(w.networks[0].widths.begin(), w.networks[0].widths.end(), d.ddpg().actor().widths().begin(),
                         d.ddpg().actor().widths().end()));
}

}  // namespace
}  // namespace pamdp
