// A network's parameters by name, not owned: what a learner publishes and an actor's acting
// policy loads (the NamedNetwork of schemas/messages.fbs).
#pragma once

#include <span>
#include <string_view>

namespace pamdp {

struct NetworkView {
  std::string_view name;
  std::span<const int> widths;    // layer widths, input first
  std::span<const float> params;  // Mlp's flat layout
};

}  // namespace pamdp
