// The text picture of an env's state that pamdp.Env.render("ansi") returns: the positions the
// env's own state holds (HFO: the half field drawn in characters, agent, ball and goalie; the
// toy tasks: their few numbers), not its observation. Allocates a string; for humans, not for
// the step loop. `env` is any Env build_env() makes (a scaled-parameters wrapper is looked
// through); an env with no state to show (the real HFO server) gets its name and status only.
#pragma once

#include <string>

#include "envs/env.hpp"

namespace pamdp::python {

// `status` is the last step's status (0 after a reset); `steps` the steps since the reset.
std::string field_text(Env& env, int status, int steps);

}  // namespace pamdp::python
