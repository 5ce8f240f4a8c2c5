// core/: Rng, ActionSpace, RandomPolicy; and the FlatBuffers EpisodeReport wire format.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include "core/action_space.hpp"
#include "core/normal.hpp"
#include "core/policy.hpp"
#include "core/rng.hpp"
#include "core/transport.hpp"
#include "schemas/episode_generated.h"

namespace pamdp {
namespace {

// ---------------------------------------------------------------------------------------------
// Rng

// The published algorithms, written out independently of core/rng.hpp: splitmix64 (seeding)
// and xoshiro256++ (Blackman & Vigna, https://prng.di.unimi.it/xoshiro256plusplus.c).
uint64_t splitmix64(uint64_t& x) {
  uint64_t z = (x += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

struct ReferenceXoshiro {
  std::array<uint64_t, 4> s{};
  static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  uint64_t next() {
    const uint64_t result = rotl(s[0] + s[3], 23) + s[0];
    const uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl(s[3], 45);
    return result;
  }
};

TEST(Rng, SeedsThroughSplitmix64) {
  // Known splitmix64 outputs for seed 0.
  const Rng rng(0);
  EXPECT_EQ(rng.state()[0], 0xE220A8397B1DCDAFULL);
  EXPECT_EQ(rng.state()[1], 0x6E789E6AA1B965F4ULL);
  EXPECT_EQ(rng.state()[2], 0x06C45D188009454FULL);
  EXPECT_EQ(rng.state()[3], 0xF88BB8A8724C81ECULL);
}

TEST(Rng, MatchesReferenceXoshiro256PlusPlus) {
  for (uint64_t seed : {0ULL, 1ULL, 0xDEADBEEFULL, ~0ULL}) {
    uint64_t x = seed;
    ReferenceXoshiro ref;
    for (auto& w : ref.s) {
      w = splitmix64(x);
    }
    Rng rng(seed);
    for (int i = 0; i < 1000; ++i) {
      ASSERT_EQ(rng.next_u64(), ref.next()) << "seed " << seed << " draw " << i;
    }
  }
}

TEST(Rng, SameSeedSameStreamDifferentSeedDifferentStream) {
  Rng a(42);
  Rng b(42);
  Rng c(43);
  int equal_to_c = 0;
  for (int i = 0; i < 1000; ++i) {
    const uint64_t va = a.next_u64();
    ASSERT_EQ(va, b.next_u64());
    equal_to_c += va == c.next_u64() ? 1 : 0;
  }
  EXPECT_EQ(equal_to_c, 0);
}

TEST(Rng, ReseedRestartsTheStream) {
  Rng fresh(7);
  Rng used(123);
  for (int i = 0; i < 37; ++i) {
    used.next_u64();
  }
  used.reseed(7);
  EXPECT_EQ(used, fresh);
  for (int i = 0; i < 100; ++i) {
    ASSERT_EQ(used.next_u64(), fresh.next_u64());
  }
}

TEST(Rng, StateRoundTripResumesTheStream) {
  Rng a(99);
  for (int i = 0; i < 10; ++i) {
    a.next_u64();
  }
  const std::array<uint64_t, 4> saved = a.state();
  std::vector<uint64_t> expected(100);
  for (uint64_t& v : expected) {
    v = a.next_u64();
  }
  Rng b(0);
  b.set_state(saved);
  EXPECT_NE(b, a);
  for (int i = 0; i < 100; ++i) {
    ASSERT_EQ(b.next_u64(), expected[static_cast<size_t>(i)]);
  }
  EXPECT_EQ(b, a);
}

TEST(Rng, CopiesAreIndependentAndEqual) {
  Rng a(5);
  Rng b = a;
  EXPECT_EQ(a, b);
  a.next_u64();
  EXPECT_NE(a, b);
  b.next_u64();
  EXPECT_EQ(a, b);
}

// Statistical checks on n = 200000 draws. Tolerances are about 6 standard errors of each
// estimate, so a correct generator fails with probability far below 1e-6 (and the seed is fixed).
constexpr int kDraws = 200000;

TEST(Rng, UniformStaysInRangeWithMeanAndVarianceOfU01) {
  Rng rng(2016);
  double sum = 0.0;
  double sum2 = 0.0;
  for (int i = 0; i < kDraws; ++i) {
    const double u = rng.uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    sum += u;
    sum2 += u * u;
  }
  const double mean = sum / kDraws;
  const double var = sum2 / kDraws - mean * mean;
  // se(mean) = sqrt(1/12 / n) = 6.5e-4; se(var) = sqrt(1/180 / n) = 1.7e-4.
  EXPECT_NEAR(mean, 0.5, 0.004);
  EXPECT_NEAR(var, 1.0 / 12.0, 0.001);
}

TEST(Rng, UniformInRangeStaysInRangeWithMidpointMean) {
  Rng rng(3);
  const double lo = -180.0;
  const double hi = 180.0;
  double sum = 0.0;
  for (int i = 0; i < kDraws; ++i) {
    const double u = rng.uniform(lo, hi);
    ASSERT_GE(u, lo);
    ASSERT_LT(u, hi);
    sum += u;
  }
  // se = 360 * sqrt(1/12 / n) = 0.23.
  EXPECT_NEAR(sum / kDraws, 0.0, 1.5);
}

TEST(Rng, BelowCoversEveryValueEvenly) {
  Rng rng(4);
  constexpr int kN = 10;
  std::array<int, kN> counts{};
  for (int i = 0; i < kDraws; ++i) {
    const uint64_t k = rng.below(kN);
    ASSERT_LT(k, static_cast<uint64_t>(kN));
    ++counts[k];
  }
  // Each count ~ Binomial(n, 0.1): mean 20000, sd 134.
  for (int k = 0; k < kN; ++k) {
    EXPECT_NEAR(counts[static_cast<size_t>(k)], kDraws / double{kN}, 800.0) << "value " << k;
  }
  EXPECT_EQ(rng.below(1), 0U);
}

TEST(Rng, NormalHasZeroMeanUnitVariance) {
  Rng rng(5);
  double sum = 0.0;
  double sum2 = 0.0;
  for (int i = 0; i < kDraws; ++i) {
    const double z = rng.normal();
    ASSERT_TRUE(std::isfinite(z));
    sum += z;
    sum2 += z * z;
  }
  const double mean = sum / kDraws;
  const double var = sum2 / kDraws - mean * mean;
  // se(mean) = 2.2e-3; se(var) = sqrt(2 / n) = 3.2e-3.
  EXPECT_NEAR(mean, 0.0, 0.015);
  EXPECT_NEAR(var, 1.0, 0.02);
}

// The ziggurat's draws against the standard normal's CDF at points in every region it samples
// differently: the layers' cores (|z| < 1), their wedges, the base strip and the tail beyond
// r = 3.654 (2.6e-4 of the mass). 4 M draws: the binomial standard error of each fraction is
// at most 2.5e-4, at the tail point 8e-6; the bounds are 4 of them.
TEST(ZigguratNormal, MatchesTheStandardNormal) {
  Rng rng(11);
  constexpr int kN = 4'000'000;
  constexpr std::array<double, 7> kPoints{0.0, 0.5, 1.0, 2.0, 3.0, 3.6541528853610088, 4.5};
  std::array<int64_t, kPoints.size()> above{};
  double sum = 0.0;
  double sum2 = 0.0;
  double sum4 = 0.0;
  for (int i = 0; i < kN; ++i) {
    const double z = ziggurat_normal(rng);
    ASSERT_TRUE(std::isfinite(z));
    sum += z;
    sum2 += z * z;
    sum4 += z * z * z * z;
    for (size_t k = 0; k < kPoints.size(); ++k) {
      above[k] += std::fabs(z) > kPoints[k] ? 1 : 0;
    }
  }
  EXPECT_NEAR(sum / kN, 0.0, 4.0 * 5e-4);
  EXPECT_NEAR(sum2 / kN, 1.0, 4.0 * 7.1e-4);
  EXPECT_NEAR(sum4 / kN, 3.0, 4.0 * 4.9e-3);  // E z^4 = 3, sd(z^4) = sqrt(96)
  for (size_t k = 0; k < kPoints.size(); ++k) {
    const double p = std::erfc(kPoints[k] / std::sqrt(2.0));  // P(|z| > t)
    const double se = std::sqrt(p * (1.0 - p) / kN);
    EXPECT_NEAR(static_cast<double>(above[k]) / kN, p, 4.0 * se + 1e-7) << "P(|z| > " << kPoints[k] << ")";
  }
}

// ---------------------------------------------------------------------------------------------
// ActionSpace

ActionSpace test_space() {
  return ActionSpace{
      .actions = {{"DASH", {0, 1}}, {"TURN", {2}}, {"NOOP", {}}, {"KICK", {3, 1}}},
      .params = {{"power", 0.0F, 100.0F}, {"dir", -180.0F, 180.0F}, {"turn", -30.0F, 30.0F}, {"kick", 0.5F, 1.5F}},
  };
}

TEST(ActionSpace, SizesAndOutputWidth) {
  const ActionSpace space = test_space();
  EXPECT_EQ(space.num_actions(), 4);
  EXPECT_EQ(space.num_params(), 4);
  EXPECT_EQ(space.output_width(), 8);
  const ActionSpace empty;
  EXPECT_EQ(empty.num_actions(), 0);
  EXPECT_EQ(empty.output_width(), 0);
}

TEST(ActionSpace, FindActionByName) {
  const ActionSpace space = test_space();
  EXPECT_EQ(space.find_action("DASH"), 0);
  EXPECT_EQ(space.find_action("TURN"), 1);
  EXPECT_EQ(space.find_action("KICK"), 3);
  EXPECT_EQ(space.find_action("kick"), -1);  // names are case-sensitive
  EXPECT_EQ(space.find_action(""), -1);
  EXPECT_EQ(space.find_action("TACKLE"), -1);
}

// ---------------------------------------------------------------------------------------------
// RandomPolicy

TEST(RandomPolicy, ParamsStayInBoundsAndEveryActionIsDrawn) {
  const ActionSpace space = test_space();
  RandomPolicy policy(space, 1);
  const std::vector<float> obs(3, 0.0F);
  std::array<int, 4> counts{};
  constexpr int kActs = 40000;
  for (int i = 0; i < kActs; ++i) {
    const ParamAction a = policy.act(obs);
    ASSERT_GE(a.id, 0);
    ASSERT_LT(a.id, space.num_actions());
    ++counts[static_cast<size_t>(a.id)];
    ASSERT_EQ(a.params.size(), space.params.size());
    for (size_t p = 0; p < a.params.size(); ++p) {
      ASSERT_GE(a.params[p], space.params[p].lo) << space.params[p].name;
      ASSERT_LE(a.params[p], space.params[p].hi) << space.params[p].name;
    }
  }
  // Uniform over 4 actions: each count ~ Binomial(40000, 0.25), sd 87.
  for (int c : counts) {
    EXPECT_NEAR(c, kActs / 4.0, 500.0);
  }
}

TEST(RandomPolicy, OnlyAllowedActionsAreDrawn) {
  const ActionSpace space = test_space();
  RandomPolicy policy(space, 2, {1, 3});
  const std::vector<float> obs(3, 0.0F);
  std::array<int, 4> counts{};
  for (int i = 0; i < 10000; ++i) {
    ++counts[static_cast<size_t>(policy.act(obs).id)];
  }
  EXPECT_EQ(counts[0], 0);
  EXPECT_EQ(counts[2], 0);
  EXPECT_GT(counts[1], 4000);
  EXPECT_GT(counts[3], 4000);
}

TEST(RandomPolicy, RejectsAllowedActionOutOfRange) {
  const ActionSpace space = test_space();
  EXPECT_THROW(RandomPolicy(space, 1, {0, 4}), std::invalid_argument);
  EXPECT_THROW(RandomPolicy(space, 1, {-1}), std::invalid_argument);
}

TEST(RandomPolicy, SetParamRangeOverridesTheSpaceBounds) {
  const ActionSpace space = test_space();
  RandomPolicy policy(space, 3);
  policy.set_param_range(0, -100.0F, 100.0F);  // the paper's dash power draw
  const std::vector<float> obs(3, 0.0F);
  int negative = 0;
  double sum = 0.0;
  constexpr int kActs = 20000;
  for (int i = 0; i < kActs; ++i) {
    const ParamAction a = policy.act(obs);
    ASSERT_GE(a.params[0], -100.0F);
    ASSERT_LE(a.params[0], 100.0F);
    negative += a.params[0] < 0.0F ? 1 : 0;
    sum += a.params[0];
    ASSERT_GE(a.params[1], -180.0F);  // other parameters keep their bounds
    ASSERT_LE(a.params[1], 180.0F);
  }
  // se(mean) = 200 * sqrt(1/12 / n) = 0.41.
  EXPECT_NEAR(sum / kActs, 0.0, 2.5);
  EXPECT_NEAR(negative, kActs / 2.0, 500.0);
  EXPECT_THROW(policy.set_param_range(4, 0.0F, 1.0F), std::out_of_range);
}

TEST(RandomPolicy, SameSeedSameActions) {
  const ActionSpace space = test_space();
  RandomPolicy a(space, 77);
  RandomPolicy b(space, 77);
  const std::vector<float> obs(3, 0.0F);
  for (int i = 0; i < 1000; ++i) {
    const ParamAction pa = a.act(obs);
    const std::vector<float> params_a(pa.params.begin(), pa.params.end());
    const ParamAction pb = b.act(obs);
    ASSERT_EQ(pa.id, pb.id);
    ASSERT_EQ(params_a, std::vector<float>(pb.params.begin(), pb.params.end()));
  }
}

// ---------------------------------------------------------------------------------------------
// FlatBuffers EpisodeReport

flatbuffers::DetachedBuffer build_report(flatbuffers::FlatBufferBuilder& fbb) {
  wire::EpisodeReportBuilder b(fbb);
  b.add_actor_id(17);
  b.add_episode(1234567890123ULL);
  b.add_return_(-3.25F);
  b.add_steps(412);
  b.add_status(4);
  b.add_policy_version(99);
  wire::FinishEpisodeReportBuffer(fbb, b.Finish());
  return fbb.Release();
}

bool verifies(const uint8_t* data, size_t size) {
  flatbuffers::Verifier verifier(data, size);
  return wire::VerifyEpisodeReportBuffer(verifier);
}

TEST(EpisodeReport, RoundTripsThroughBuilderAndVerifier) {
  flatbuffers::FlatBufferBuilder fbb;
  const flatbuffers::DetachedBuffer buf = build_report(fbb);
  ASSERT_TRUE(verifies(buf.data(), buf.size()));
  EXPECT_TRUE(wire::EpisodeReportBufferHasIdentifier(buf.data()));

  const wire::EpisodeReport* r = wire::GetEpisodeReport(buf.data());
  EXPECT_EQ(r->schema_version(), static_cast<uint16_t>(wire::SchemaVersion::V1));
  EXPECT_EQ(r->actor_id(), 17U);
  EXPECT_EQ(r->episode(), 1234567890123ULL);
  EXPECT_EQ(r->return_(), -3.25F);
  EXPECT_EQ(r->steps(), 412U);
  EXPECT_EQ(r->status(), 4);
  EXPECT_EQ(r->policy_version(), 99U);

  // The object API gives the same values back, and packs to a buffer that verifies again.
  const std::unique_ptr<wire::EpisodeReportT> obj(r->UnPack());
  EXPECT_EQ(obj->episode, 1234567890123ULL);
  EXPECT_EQ(obj->return_, -3.25F);
  flatbuffers::FlatBufferBuilder fbb2;
  wire::FinishEpisodeReportBuffer(fbb2, wire::EpisodeReport::Pack(fbb2, obj.get()));
  ASSERT_TRUE(verifies(fbb2.GetBufferPointer(), fbb2.GetSize()));
  EXPECT_EQ(wire::GetEpisodeReport(fbb2.GetBufferPointer())->steps(), 412U);
}

TEST(EpisodeReport, BuilderIsReusableAfterClear) {
  flatbuffers::FlatBufferBuilder fbb;
  for (uint32_t i = 0; i < 3; ++i) {
    fbb.Clear();
    wire::FinishEpisodeReportBuffer(fbb, wire::CreateEpisodeReport(fbb, 1, i, i, 0.5F, i));
    ASSERT_TRUE(verifies(fbb.GetBufferPointer(), fbb.GetSize()));
    EXPECT_EQ(wire::GetEpisodeReport(fbb.GetBufferPointer())->actor_id(), i);
  }
}

TEST(EpisodeReport, VerifierRejectsCorruptBuffers) {
  flatbuffers::FlatBufferBuilder fbb;
  const flatbuffers::DetachedBuffer good = build_report(fbb);
  const std::vector<uint8_t> original(good.data(), good.data() + good.size());
  ASSERT_TRUE(verifies(original.data(), original.size()));

  {  // Root offset pointing far outside the buffer.
    std::vector<uint8_t> bad = original;
    const uint32_t huge = 0x7FFFFFF0U;
    std::memcpy(bad.data(), &huge, sizeof(huge));
    EXPECT_FALSE(verifies(bad.data(), bad.size()));
  }
  {  // Wrong file identifier (bytes 4..7 hold "PEPR").
    std::vector<uint8_t> bad = original;
    bad[4] = 'X';
    EXPECT_FALSE(verifies(bad.data(), bad.size()));
  }
  {  // The table's vtable offset (the first 4 bytes of the table) pointing outside.
    std::vector<uint8_t> bad = original;
    uint32_t root = 0;
    std::memcpy(&root, bad.data(), sizeof(root));
    ASSERT_LT(root + 4U, bad.size());
    const int32_t far = -0x40000000;
    std::memcpy(bad.data() + root, &far, sizeof(far));
    EXPECT_FALSE(verifies(bad.data(), bad.size()));
  }
  // Every truncation (a partly received message) is rejected.
  for (size_t size = 0; size < original.size(); ++size) {
    EXPECT_FALSE(verifies(original.data(), size)) << "truncated to " << size << " of " << original.size();
  }
}

}  // namespace
}  // namespace pamdp

namespace {

// pamdp keygen's files: created 0600, never overwritten, and refused once readable by everyone.
TEST(CurveKeys, WrittenPrivateRefusedWhenWorldReadable) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(::testing::TempDir()) / ("pamdp_keys_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  pamdp::net::write_curve_keyring(dir.string());
  for (const char* name : {"server.keys", "client.keys"}) {
    const auto perms = fs::status(dir / name).permissions();
    EXPECT_EQ(perms & (fs::perms::group_all | fs::perms::others_all), fs::perms::none) << name;
  }
  EXPECT_NO_THROW(pamdp::net::load_curve_keyring(dir.string(), /*need_server=*/true));
  EXPECT_THROW(pamdp::net::write_curve_keyring(dir.string()), std::runtime_error);  // never overwrites

  fs::permissions(dir / "client.keys", fs::perms::others_read, fs::perm_options::add);
  try {
    pamdp::net::load_curve_keyring(dir.string(), /*need_server=*/false);
    ADD_FAILURE() << "a world-readable key file was accepted";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("readable by every user"), std::string::npos) << what;
    EXPECT_NE(what.find("chmod 600"), std::string::npos) << what;
  }
  fs::remove_all(dir);
}

}  // namespace

namespace {

// Which binds and joins stay on this machine (issue 33: anything else needs CURVE or insecure).
TEST(Transport, LoopbackEndpoints) {
  using pamdp::net::is_loopback_endpoint;
  for (const char* local :
       {"tcp://127.0.0.1:5555", "tcp://127.0.0.1:0", "tcp://127.0.0.1:*", "tcp://127.1.2.3:9", "tcp://localhost:5555",
        "tcp://[::1]:5555", "tcp://lo:5555", "inproc://x", "ipc:///tmp/s"}) {
    EXPECT_TRUE(is_loopback_endpoint(local)) << local;
  }
  for (const char* exposed :
       {"tcp://*:5555", "tcp://0.0.0.0:5555", "tcp://[::]:5555", "tcp://10.0.0.5:5555", "tcp://eth0:5555",
        "tcp://learner:5555", "tcp://128.0.0.1:1", "tcp://127.0.0.1.evil:1", "tcp://127.0.0.1;10.0.0.5:1",
        "tcp://127.0.0.256:1", "udp://127.0.0.1:1", "tcp://127.0.0.1", ""}) {
    EXPECT_FALSE(is_loopback_endpoint(exposed)) << exposed;
  }
}

}  // namespace
