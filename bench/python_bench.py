#!/usr/bin/env python3
"""The Python module's speed against the C++ simulator (issue 30), printed as a table.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_bench.py [--build build] [--seconds 2]

Rows: BM_SimStep (pamdp-bench, C++, the reference); one env's step() from Python with the same
fixed action cycle as BM_SimStep (its overhead over the C++ step is the binding's cost); the
vector env with random actions drawn in Python by action_space.sample() every step (N = 64 on
one thread, hence one core, and a few other shapes); the team vector env, 64 games of 2v1.
Each Python figure is the median of 3 runs. Targets: vector env >= 1 M env steps/s for N = 64
on one core; single step <= 3 us of overhead. For scale: EnvPool's published ~1 M Atari
frames/s and ~3 M MuJoCo steps/s use 256 CPU cores (a DGX-A100), i.e. ~4 k and ~12 k per core;
the real HFO server runs "several hundred FPS" (LARG/HFO issue #60).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np

import pamdp


def cpp_sim_step_ns(build: str) -> float:
    """BM_SimStep's time per step in ns, median of 3 repetitions."""
    out = subprocess.run(
        [os.path.join(build, "bin", "pamdp-bench"), "--benchmark_filter=^BM_SimStep$", "--benchmark_format=json",
         "--benchmark_repetitions=3", "--benchmark_min_time=0.5"],
        check=True, capture_output=True, text=True)
    runs = [b for b in json.loads(out.stdout)["benchmarks"] if b.get("run_type") == "iteration"]
    return statistics.median(b["real_time"] * {"ns": 1, "us": 1e3, "ms": 1e6}[b["time_unit"]] for b in runs)


def median_of_3(fn):
    return statistics.median(fn() for _ in range(3))


def single_step_ns(seconds: float, per_action_tuple: bool) -> float:
    """ns per env.step() of hfo-1v0 from Python, BM_SimStep's action cycle, resets excluded."""
    env = pamdp.make("hfo-1v0")
    env.reset(seed=7)
    flat = np.array([80.0, 0.0, 30.0, 0.0, 60.0, 10.0], np.float32)
    per_action = (flat[0:2], flat[2:3], flat[3:4], flat[4:6])
    params = per_action if per_action_tuple else flat
    cycle = [(i, params) for i in (0, 0, 1, 0, 3, 0, 0, 3)]
    step, reset = env.step, env.reset

    def run():
        n, t_reset = 0, 0.0
        start = time.perf_counter()
        while time.perf_counter() - start < seconds:
            for action in cycle * 100:
                _, _, terminated, truncated, _ = step(action)
                if terminated or truncated:
                    r0 = time.perf_counter()
                    reset()
                    t_reset += time.perf_counter() - r0
            n += 800
        return (time.perf_counter() - start - t_reset) / n * 1e9

    return median_of_3(run)


def vector_steps_per_s(seconds: float, num_envs: int, num_threads: int, copy: bool, env_id="hfo-1v0",
                       agents: int = 0) -> float:
    """Env steps (games' cycles) per second of make_vec, or of make_team_vec with `agents`
    players a game, with random actions sampled in Python every step."""
    if agents:
        vec = pamdp.make_team_vec(env_id, agents=agents, num_envs=num_envs, num_threads=num_threads, copy=copy)
    else:
        vec = pamdp.make_vec(env_id, num_envs=num_envs, num_threads=num_threads, copy=copy)
    vec.reset(seed=1)
    vec.action_space.seed(1)
    sample, step = vec.action_space.sample, vec.step

    def run():
        n = 0
        start = time.perf_counter()
        while time.perf_counter() - start < seconds:
            for _ in range(50):
                step(sample())
            n += 50
        return n * num_envs / (time.perf_counter() - start)

    return median_of_3(run)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", default="build", help="the build directory holding bin/pamdp-bench")
    parser.add_argument("--seconds", type=float, default=2.0, help="length of each timed run")
    args = parser.parse_args()

    cpp_ns = cpp_sim_step_ns(args.build)
    rows = [("BM_SimStep (C++, hfo-1v0, one core)", cpp_ns, "reference")]
    for per_action in (False, True):
        ns = single_step_ns(args.seconds, per_action)
        form = "per-action tuple" if per_action else "flat array"
        rows.append((f"env.step() from Python ({form})", ns, f"overhead {(ns - cpp_ns) / 1e3:.2f} us (target <= 3)"))
    for num_envs, threads, copy in ((64, 1, True), (64, 1, False), (256, 1, True), (256, 2, True)):
        rate = vector_steps_per_s(args.seconds, num_envs, threads, copy)
        target = " (target >= 1 M/s)" if (num_envs, threads, copy) == (64, 1, True) else ""
        rows.append((f"make_vec N={num_envs} threads={threads} copy={copy}, random actions", 1e9 / rate,
                     f"{rate / 1e6:.2f} M env steps/s{target}"))
    rate = vector_steps_per_s(args.seconds, 64, 1, True, "hfo-1v1")
    rows.append(("make_vec hfo-1v1 N=64 threads=1, random actions", 1e9 / rate, f"{rate / 1e6:.2f} M env steps/s"))
    rate = vector_steps_per_s(args.seconds, 64, 1, True, "hfo-1v1", agents=2)
    rows.append(("make_team_vec hfo-1v1 agents=2 N=64 threads=1 (2v1)", 1e9 / rate,
                 f"{rate / 1e6:.2f} M games' cycles/s, {2 * rate / 1e6:.2f} M player steps/s"))

    print(f"{'measurement':<58} {'ns/step':>9} {'steps/s':>11} {'x BM_SimStep':>13}  note")
    for name, ns, note in rows:
        print(f"{name:<58} {ns:9.0f} {1e9 / ns:11,.0f} {cpp_ns / ns:13.2f}  {note}")
    print("for scale: EnvPool ~1 M Atari frames/s, ~3 M MuJoCo steps/s on 256 cores (~4 k, ~12 k per core); "
          "the real HFO server: several hundred FPS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
