"""Diffs run_gym_goal.py's and run_goal_env's outputs: same episodes, same decision steps, same
internal step counts and terminal flags, rewards within 1e-5 (ours are float32), states within
--tol. Exits 1 on a difference."""
import sys

a = open(sys.argv[1]).read().split('\n')
b = open(sys.argv[2]).read().split('\n')
tol = float(sys.argv[3]) if len(sys.argv) > 3 else 1e-9
if len(a) != len(b):
    sys.exit('different numbers of lines: %d (gym-goal) and %d (ours)' % (len(a), len(b)))
worst = 0.0
steps = 0
for i, (x, y) in enumerate(zip(a, b)):
    xs, ys = x.split(), y.split()
    if not xs:
        continue
    if xs[0] != ys[0]:
        sys.exit('line %d: %s vs %s' % (i + 1, x[:80], y[:80]))
    if xs[0] == 'S':
        steps += 1
        if xs[1] != ys[1] or xs[3] != ys[3]:
            sys.exit('line %d: sim steps or terminal differ: %s vs %s' % (i + 1, x[:80], y[:80]))
        if abs(float(xs[2]) - float(ys[2])) > 1e-5 * max(1.0, abs(float(xs[2]))):
            sys.exit('line %d: reward %s vs %s' % (i + 1, xs[2], ys[2]))
        xs, ys = xs[4:], ys[4:]
    else:
        xs, ys = xs[1:], ys[1:]
    worst = max([worst] + [abs(float(p) - float(q)) for p, q in zip(xs, ys)])
    if worst > tol:
        sys.exit('line %d: state differs by %g' % (i + 1, worst))
print('%d episodes, %d decision steps agree; largest state difference %.3g' % (sum(l.startswith('R') for l in a), steps, worst))
