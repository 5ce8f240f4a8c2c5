#include "core/action_space.hpp"

namespace pamdp {

int ActionSpace::find_action(std::string_view name) const {
  for (int i = 0; i < num_actions(); ++i) {
    if (actions[static_cast<size_t>(i)].name == name) {
      return i;
    }
  }
  return -1;
}

}  // namespace pamdp
