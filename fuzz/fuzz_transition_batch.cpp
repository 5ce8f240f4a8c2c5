// TransitionBatch validation (wire::valid_batch, then rows_of) on batches whose claimed widths
// and count disagree with their arrays in every way: the fuzzed bytes choose the claims, the
// widths the receiver expects, each array's length and the floats (NaN and infinities included).
// A batch that valid_batch accepts must be readable in full through rows_of's views.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "core/wire.hpp"

namespace {

class Bytes {
 public:
  Bytes(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  template <typename T>
  T take() {
    T v{};
    const size_t n = std::min(sizeof(T), size_ - pos_);
    std::memcpy(&v, data_ + pos_, n);
    pos_ += n;
    return v;
  }
  float next_float() {
    if (size_ == 0) {
      return 0.0F;
    }
    float v = 0.0F;
    uint8_t b[4];
    for (auto& x : b) {
      x = data_[cycle_++ % size_];
    }
    std::memcpy(&v, b, 4);
    return v;
  }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  size_t cycle_ = 0;
};

volatile float g_sink = 0.0F;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace pamdp::wire;
  Bytes in(data, size);
  const uint32_t obs = in.take<uint8_t>() % 70;
  const uint32_t act = in.take<uint8_t>() % 12;
  const uint32_t count = in.take<uint16_t>() % 300;
  const uint32_t expect_obs = (in.take<uint8_t>() & 1) != 0 ? obs : in.take<uint8_t>() % 70;
  const uint32_t expect_act = (in.take<uint8_t>() & 1) != 0 ? act : in.take<uint8_t>() % 12;
  const uint32_t max_count = in.take<uint16_t>() % 512;
  // Each array's length: right for the claims, or off by a fuzzed amount.
  auto length = [&](size_t right) -> size_t {
    const uint8_t how = in.take<uint8_t>();
    if ((how & 3) != 0) {
      return right;
    }
    return (how >> 2) % 2 == 0 ? right + (how >> 3) : right - std::min<size_t>(right, how >> 3);
  };
  std::vector<std::vector<float>> floats;
  for (size_t right : {size_t{count} * obs, size_t{count} * act, size_t{count}, size_t{count} * obs, size_t{count}}) {
    std::vector<float> v(length(right));
    for (float& x : v) {
      x = in.next_float();
    }
    floats.push_back(std::move(v));
  }
  std::vector<uint8_t> terminals(length(count));
  for (auto& t : terminals) {
    t = in.take<uint8_t>();
  }
  const uint8_t missing = in.take<uint8_t>();  // bit i: leave array i out

  flatbuffers::FlatBufferBuilder fbb(1024);
  auto vec = [&](int i) { return (missing >> i) & 1 ? 0 : fbb.CreateVector(floats[static_cast<size_t>(i)]).o; };
  const auto states = flatbuffers::Offset<flatbuffers::Vector<float>>(vec(0));
  const auto actions = flatbuffers::Offset<flatbuffers::Vector<float>>(vec(1));
  const auto rewards = flatbuffers::Offset<flatbuffers::Vector<float>>(vec(2));
  const auto next_states = flatbuffers::Offset<flatbuffers::Vector<float>>(vec(3));
  const auto returns = flatbuffers::Offset<flatbuffers::Vector<float>>(vec(4));
  const auto terms =
      (missing >> 5) & 1 ? flatbuffers::Offset<flatbuffers::Vector<uint8_t>>() : fbb.CreateVector(terminals);
  const auto batch =
      CreateTransitionBatch(fbb, 1, 2, obs, act, count, states, actions, rewards, next_states, terms, returns);
  EnvelopeBuilder env(fbb);
  env.add_schema_version(kSchemaVersion);
  env.add_payload_type(Payload::TransitionBatch);
  env.add_payload(batch.Union());
  FinishEnvelopeBuffer(fbb, env.Finish());

  const Envelope* opened = open_envelope(bytes_of(fbb));
  if (opened == nullptr) {
    __builtin_trap();  // a buffer our own builder wrote must open
  }
  const TransitionBatch* b = opened->payload_as_TransitionBatch();
  if (!valid_batch(b, expect_obs, expect_act, max_count)) {
    return 0;
  }
  const TransitionRows r = rows_of(b);
  if (r.count != count || r.obs_dim != expect_obs || r.action_dim != expect_act || r.count > max_count) {
    __builtin_trap();
  }
  float sum = 0.0F;
  for (size_t i = 0; i < size_t{r.count} * r.obs_dim; ++i) {
    sum += r.states[i] + r.next_states[i];
  }
  for (size_t i = 0; i < size_t{r.count} * r.action_dim; ++i) {
    sum += r.actions[i];
  }
  for (size_t i = 0; i < r.count; ++i) {
    sum += r.rewards[i] + r.mc_returns[i] + static_cast<float>(r.terminals[i]);
  }
  g_sink = sum;
  return 0;
}
