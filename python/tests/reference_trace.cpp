// The C++ side of python_reference_test: plays an env built the way `pamdp` builds it (the config
// reader and app::make_env, not the Python module's registry) with actions read from a file, and
// prints every observation, reward and status exactly (%.9g round-trips a float).
//
// Usage: reference_trace SEED ACTIONS.csv [env.KEY=VALUE ...]
// ACTIONS.csv: one action per line, "id,p0,p1,...": the env's whole parameter vector.
// Output: "R,obs..." after every reset (the first with SEED, later ones continuing the env's
// stream, after each terminal step) and "S,reward,status,obs..." after every step.
#include <cstdio>
#include <exception>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "app/env_factory.hpp"
#include "app/experiment_config.hpp"

namespace {

void print(const char* tag, const std::vector<float>& obs, const pamdp::StepResult* r) {
  std::printf("%s", tag);
  if (r != nullptr) {
    std::printf(",%.9g,%d", static_cast<double>(r->reward), r->status);
  }
  for (float x : obs) {
    std::printf(",%.9g", static_cast<double>(x));
  }
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: reference_trace SEED ACTIONS.csv [env.KEY=VALUE ...]\n");
    return 2;
  }
  try {
    const std::vector<std::string> sets(argv + 3, argv + argc);
    const pamdp::app::ExperimentConfig c = pamdp::app::parse_experiment_config("", "reference_trace", sets);
    auto env = pamdp::app::make_env(c.env);
    std::vector<float> obs(static_cast<size_t>(env->observation_size()));
    std::vector<float> params(static_cast<size_t>(env->action_space().num_params()));
    env->reset(std::stoull(argv[1]), obs);
    print("R", obs, nullptr);
    std::ifstream in(argv[2]);
    std::string line;
    while (std::getline(in, line)) {
      std::stringstream ss(line);
      std::string field;
      std::getline(ss, field, ',');
      const int id = std::stoi(field);
      for (float& p : params) {
        std::getline(ss, field, ',');
        p = std::stof(field);
      }
      const pamdp::StepResult r = env->step({id, params}, obs);
      print("S", obs, &r);
      if (r.terminal()) {
        env->reset(obs);
        print("R", obs, nullptr);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "reference_trace: %s\n", e.what());
    return 1;
  }
  return 0;
}
