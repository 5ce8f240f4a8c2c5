#!/usr/bin/python3
"""Record team games (2v0, 2v1, and against agent2d's field defenders: 1v2, 2v2, 1v3) on the
real HFO server and turn its logs (and the defenders' own .dcl debug logs) into per-cycle CSV.

Subcommands (see README.md next to this file):

  record  start bin/HFO (noise off, .rcg/.rcl logging on), drive its N offense-agent slots
          with random and scripted low-level policies, one process per agent
  agent   (internal) one HFO agent process, started by `record`
  parse   read a recording's .rcg/.rcl, the agents' own step logs and the defenders' .dcl
          files, write one row per cycle
  subset  pick whole episodes from parsed recordings into a compact CSV for the tests

Only the Python standard library and numpy are used.
"""

import argparse
import csv
import glob
import hashlib
import json
import math
import os
import random
import re
import signal
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.realpath(__file__))

# rcssserver options added to bin/HFO's own (noise off). bin/HFO has no way to pass server
# options, so `record` runs bin/HFO's own source with this string appended to its
# serverOptions (see launcher_code()).
NOISE_OFF = ('server::player_rand=0 server::ball_rand=0 server::kick_rand=0 '
             'server::tackle_rand_factor=0 server::prand_factor_l=0 server::prand_factor_r=0 '
             'server::kick_rand_factor_l=0 server::kick_rand_factor_r=0 '
             'server::wind_force=0 server::wind_rand=0 server::wind_none=1 '
             'server::wind_random=0 server::foul_detect_probability=0')

# HFO action ids (hfo/hfo.py)
DASH, TURN, TACKLE, KICK, NOOP, QUIT = 0, 1, 2, 3, 13, 14
ACT_NAME = {DASH: 'DASH', TURN: 'TURN', TACKLE: 'TACKLE', KICK: 'KICK', NOOP: 'NOOP', QUIT: 'QUIT'}
# HFO status ids
IN_GAME, GOAL, CAPTURED, OOB, OOT, SERVER_DOWN = range(6)
STATUS_NAME = ['IN_GAME', 'GOAL', 'CAPTURED_BY_DEFENSE', 'OUT_OF_BOUNDS', 'OUT_OF_TIME',
               'SERVER_DOWN']

# Field and feature constants (HFO src/feature_extractor.{h,cpp}, E3)
HALF_L, HALF_W, GOAL_HW = 52.5, 34.0, 7.01
MAX_R = math.sqrt(52.5 ** 2 + 68.0 ** 2)   # maxHFODist
BALL_DECAY = 0.94
N_BASIC, PER_PLAYER = 58, 8

MODES = ['random', 'contest', 'team', 'noisy_team']
DEFAULT_MIX = 'random:0.15,contest:0.35,team:0.3,noisy_team:0.2'


# ----------------------------------------------------------------------------------------
# small geometry helpers

def wrap(a):
    a = math.fmod(a + 180.0, 360.0)
    if a < 0:
        a += 360.0
    return a - 180.0


def ang(s, c):
    return math.degrees(math.atan2(s, c))


def prox_to_dist(f):
    return (1.0 - (f + 1.0) / 2.0) * MAX_R


# ----------------------------------------------------------------------------------------
# decoding HFO's low-level features (with --fullstate they encode the exact state)

class View:
    """What an agent knows, decoded from its own low-level feature vector."""

    def __init__(self, f, n_team, n_opp):
        self.body = ang(f[5], f[6])
        rel = ang(f[13], f[14])
        d = prox_to_dist(f[15])
        g = math.radians(rel + self.body)
        self.x = HALF_L - d * math.cos(g)
        self.y = -d * math.sin(g)
        sp = (f[4] + 1.0) / 2.0 * 0.46
        vth = math.radians(self.body - ang(f[2], f[3]))
        self.vx, self.vy = sp * math.cos(vth), sp * math.sin(vth)
        self.kickable = f[12] > 0
        rel = ang(f[51], f[52])
        d = prox_to_dist(f[53])
        g = math.radians(rel + self.body)
        self.bx = self.x + d * math.cos(g)
        self.by = self.y + d * math.sin(g)
        bs = (f[55] + 1.0) / 2.0 * 5.0
        bth = math.radians(ang(f[56], f[57]))
        self.bvx, self.bvy = bs * math.cos(bth), bs * math.sin(bth)
        self.mates = [self._player(f, N_BASIC + PER_PLAYER * i) for i in range(n_team)]
        self.opps = [self._player(f, N_BASIC + PER_PLAYER * (n_team + i)) for i in range(n_opp)]
        # after the blocks: one unum/100 per teammate, then one per opponent (-1: empty)
        u0 = N_BASIC + PER_PLAYER * (n_team + n_opp) + n_team
        self.opp_unums = [int(round(f[u0 + i] * 100)) for i in range(n_opp)]

    def _player(self, f, i):
        blk = f[i:i + PER_PLAYER]
        if not any(blk):
            return None
        rel = ang(blk[0], blk[1])
        d = prox_to_dist(blk[2])
        g = math.radians(rel + self.body)
        return (self.x + d * math.cos(g), self.y + d * math.sin(g))

    def rel_dir(self, x, y):
        return wrap(math.degrees(math.atan2(y - self.y, x - self.x)) - self.body)

    def dist(self, x, y):
        return math.hypot(x - self.x, y - self.y)


def ball_at(v, n):
    k = (1.0 - BALL_DECAY ** n) / (1.0 - BALL_DECAY)
    return v.bx + v.bvx * k, v.by + v.bvy * k


def intercept(v, px, py, body=None):
    """(cycles, x, y): a rough first point where a player at (px, py) reaches the ball."""
    for n in range(0, 60):
        x, y = ball_at(v, n)
        if math.hypot(x - px, y - py) - 1.0 <= 0.95 * n:
            return n, x, y
    x, y = ball_at(v, 60)
    return 60, x, y


# ----------------------------------------------------------------------------------------
# policies: each returns (action, params)

def go_to(v, x, y, rng, tol=12.0, power=100.0):
    a = v.rel_dir(x, y)
    if v.dist(x, y) < 0.3:
        return TURN, [v.rel_dir(v.bx, v.by)]
    if abs(a) > tol:
        return TURN, [a]
    return DASH, [power, 0.0]


def random_action(rng):
    r = rng.random()
    if r < 0.32:
        return DASH, [rng.uniform(-100, 100), rng.choice([0.0, rng.uniform(-180, 180)])]
    if r < 0.54:
        return TURN, [rng.uniform(-180, 180)]
    if r < 0.80:
        return KICK, [rng.uniform(0, 100), rng.uniform(-180, 180)]
    if r < 0.97:
        return TACKLE, [rng.uniform(-180, 180)]
    return NOOP, []


def chase(v, rng):
    n, x, y = intercept(v, v.x, v.y)
    if n == 0:
        x, y = v.bx, v.by
    return go_to(v, x, y, rng, tol=10.0 if v.dist(x, y) > 3 else 25.0)


def kick_to(v, x, y, power):
    return KICK, [max(0.0, min(100.0, power)), v.rel_dir(x, y)]


def pass_power(d):
    # ball travels v0 / (1 - 0.94); aim to arrive with some speed left
    v0 = min(2.7, d * (1.0 - BALL_DECAY) * 1.6 + 0.4)
    return v0 / (0.027 * 0.8)


def policy_contest(v, rng, state):
    """Both players go for the same ball; the one on the ball waits for the other, then
    both kick (or tackle) it: player-player collisions and two kicks in one cycle."""
    mate = v.mates[0] if v.mates else None
    mate_d = math.hypot(mate[0] - v.bx, mate[1] - v.by) if mate else 99.0
    if v.kickable:
        if mate_d > 1.3 and state['held'] < 25:
            state['held'] += 1
            r = rng.random()
            if r < 0.55:
                return TURN, [v.rel_dir(v.bx, v.by) + rng.uniform(-30, 30)]
            if r < 0.8:
                tgt = mate if mate else (HALF_L, 0.0)
                return KICK, [rng.uniform(0, 12), v.rel_dir(*tgt)]
            return DASH, [rng.uniform(10, 60), v.rel_dir(v.bx, v.by)]
        state['held'] = 0
        if rng.random() < 0.12:
            return TACKLE, [v.rel_dir(v.bx, v.by) + rng.uniform(-40, 40)]
        if rng.random() < 0.5:
            return KICK, [rng.uniform(5, 90), rng.uniform(-180, 180)]
        return KICK, [rng.uniform(5, 60), v.rel_dir(HALF_L, 0.0) + rng.uniform(-60, 60)]
    # near the ball: sometimes tackle at it (it may be in reach of a tackle)
    if v.dist(v.bx, v.by) < 2.2 and rng.random() < 0.08:
        return TACKLE, [v.rel_dir(v.bx, v.by)]
    return chase(v, rng)


def policy_team(v, rng, me_unum, mate_unum, state):
    mate = v.mates[0] if v.mates else None
    goalie = v.opps[0] if v.opps else None
    # with field defenders (--defense-npcs >= 2): the goalie is the opponent with unum 1, and
    # the nearest field defender also makes the player pass or dribble away
    near = None
    if len(v.opps) > 1:
        gk = [o for o, u in zip(v.opps, v.opp_unums) if o is not None and u == 1]
        goalie = gk[0] if gk else goalie
        field = [o for o, u in zip(v.opps, v.opp_unums) if o is not None and u != 1]
        near = min(field, key=lambda o: v.dist(*o)) if field else None
    near_d = v.dist(*near) if near is not None else 99.0
    my_n, _, _ = intercept(v, v.x, v.y)
    owner = True
    if mate is not None:
        mate_n, _, _ = intercept(v, mate[0], mate[1])
        if mate_n < my_n or (mate_n == my_n and mate_unum < me_unum):
            owner = False
    if v.kickable:
        owner = True
    if owner:
        if not v.kickable:
            return chase(v, rng)
        gdist = math.hypot(HALF_L - v.x, v.y)
        gk_d = v.dist(*goalie) if goalie is not None else 99.0
        # shoot, at the side of the goal away from the goalie
        if gdist < state['shoot_dist'] or (gk_d < 7.0 and gdist < 25.0):
            if goalie is None:
                ty = rng.choice([-5.0, -2.0, 0.0, 2.0, 5.0])
            else:
                ty = 6.0 if goalie[1] < 0.0 else -6.0
            return kick_to(v, HALF_L + 1.0, ty, 100.0)
        # pass
        if mate is not None:
            gclose = gk_d < 12.0
            mate_ok = mate[0] > v.x - 4.0 and 4.0 < v.dist(*mate) < 30.0
            if goalie is not None:
                mate_ok = mate_ok and math.hypot(mate[0] - goalie[0], mate[1] - goalie[1]) > gk_d
            if mate_ok and (gclose or near_d < 5.0 or rng.random() < state['pass_p']):
                lead = min(2.0, max(0.0, HALF_L - 3.0 - mate[0]))
                tx, ty = mate[0] + lead, mate[1]
                return kick_to(v, tx, ty, pass_power(v.dist(tx, ty)))
        # dribble towards the goal, away from the goalie
        ty = state['dribble_y']
        if goalie is not None and gk_d < 15.0:
            ty = 12.0 if goalie[1] < v.y else -12.0
        elif near is not None and near_d < 10.0:
            ty = 12.0 if near[1] < v.y else -12.0
        return kick_to(v, min(HALF_L, v.x + 10.0), ty, state['dribble_power'])
    # support: get ahead of the ball, on the other side
    side = 1.0 if v.by < 0 else -1.0
    sx = min(46.0, v.bx + 11.0)
    sy = max(-24.0, min(24.0, v.by + side * 11.0))
    if v.dist(sx, sy) > 2.0:
        return go_to(v, sx, sy, rng, tol=15.0, power=state['support_power'])
    return TURN, [v.rel_dir(v.bx, v.by)]


def policy_random(v, rng):
    if rng.random() < 0.45:
        return chase(v, rng)
    return random_action(rng)


# ----------------------------------------------------------------------------------------
# the agent process

def episode_mode(seed, ep, mix):
    """Mode of episode ep, the same in every agent process of a recording."""
    h = hashlib.sha256(('%d:%d' % (seed, ep)).encode()).digest()
    u = int.from_bytes(h[:8], 'little') / 2.0 ** 64
    acc = 0.0
    for name, w in mix:
        acc += w
        if u < acc:
            return name
    return mix[-1][0]


def parse_mix(s):
    mix = []
    for part in s.split(','):
        name, w = part.split(':')
        if name not in MODES:
            raise SystemExit('unknown mode %r (modes: %s)' % (name, ', '.join(MODES)))
        mix.append((name, float(w)))
    tot = sum(w for _, w in mix)
    return [(n, w / tot) for n, w in mix]


def cmd_agent(a):
    import numpy as np
    sys.path.insert(0, a.hfo)
    from hfo import hfo as H
    env = H.HFOEnvironment()
    env.connectToServer(H.LOW_LEVEL_FEATURE_SET,
                        os.path.join(a.hfo, 'bin/teams/base/config/formations-dt'),
                        a.port, 'localhost', 'base_left', False, '')
    unum = env.getUnum()
    n_team, n_opp = env.getNumTeammates(), env.getNumOpponents()
    nf = env.getStateSize()
    mix = parse_mix(a.mix)
    rng = random.Random(a.seed * 1000 + a.index)
    feats, acts, params, stats, eps = [], [], [], [], []
    ep = 0
    mode = episode_mode(a.seed, ep, mix)
    state = new_episode_state(rng)
    mate_unum = 11 if unum == 7 else 7
    print('agent %d: unum %d, %d teammates, %d opponents, %d features' %
          (a.index, unum, n_team, n_opp, nf), flush=True)
    while True:
        f = env.getState().copy()
        v = View(f, n_team, n_opp)
        if mode == 'random':
            act, p = policy_random(v, rng)
        elif mode == 'contest':
            act, p = policy_contest(v, rng, state)
        elif mode == 'team':
            act, p = policy_team(v, rng, unum, mate_unum, state)
        else:
            if rng.random() < 0.25:
                act, p = random_action(rng)
            else:
                act, p = policy_team(v, rng, unum, mate_unum, state)
        env.act(act, *p)
        st = env.step()
        feats.append(f)
        acts.append(act)
        params.append((p + [math.nan, math.nan])[:2])
        stats.append(st)
        eps.append(ep)
        if st == SERVER_DOWN:
            break
        if st != IN_GAME:
            ep += 1
            mode = episode_mode(a.seed, ep, mix)
            state = new_episode_state(rng)
    np.savez_compressed(os.path.join(a.out, 'agent%d.npz' % a.index),
                        features=np.array(feats, dtype=np.float32),
                        action=np.array(acts, dtype=np.int32),
                        params=np.array(params, dtype=np.float32),
                        status=np.array(stats, dtype=np.int32),
                        episode=np.array(eps, dtype=np.int32),
                        unum=np.int32(unum), n_team=np.int32(n_team), n_opp=np.int32(n_opp))
    print('agent %d: %d steps, %d episodes' % (a.index, len(acts), ep), flush=True)


def new_episode_state(rng):
    return {'pass_p': rng.choice([0.0, 0.05, 0.15, 0.3]),
            'dribble_power': rng.uniform(8, 22),
            'shoot_dist': rng.uniform(10, 16),
            'dribble_y': rng.uniform(-6, 6),
            'support_power': rng.choice([60.0, 100.0]),
            'held': 0}


# ----------------------------------------------------------------------------------------
# record: the server plus N agent processes

LAUNCHER = r'''
import os, sys, types
src_path = sys.argv[1]
extra = os.environ['HFO_RECORD_EXTRA_OPTIONS']
src = open(src_path).read()
hook = "  if args.deterministic:"
assert src.count(hook) == 1, "bin/HFO changed: cannot add server options"
src = src.replace(hook, "  serverOptions += ' ' + %r\n" % extra + hook)
bin_dir = os.path.dirname(os.path.realpath(src_path))
dcl_unums = os.environ.get('HFO_RECORD_DCL_UNUMS', '').split()
if dcl_unums:
    # bin/Teams.py, Agent2d.launch_npc: give the defense NPCs listed agent2d's player option
    # --debug_server_logging (librcsc PlayerConfig; each writes LOG_DIR/base_right-UNUM.dcl).
    # The module is built here from Teams.py's source with one line added, and put into
    # sys.modules before bin/HFO's Trainer imports it; the file itself is not touched.
    t_path = os.path.join(bin_dir, 'Teams.py')
    t_src = open(t_path).read()
    i = t_src.index('class Agent2d(Team):')
    j = t_src.find('\nclass ', i)
    j = len(t_src) if j < 0 else j
    seg = t_src[i:j]
    t_hook = "    return self.start_npc_proc(launchOpts)\n"
    assert seg.count(t_hook) == 1 and "print('Launch npc %s-%d' % (self._name, player_num))" \
        in seg, "bin/Teams.py changed: cannot add --debug_server_logging"
    add = ("    if self._name == 'base_right' and player_num in %r:\n"
           "      launchOpts = ((launchOpts or '') + ' --debug_server_logging').strip()\n"
           % (tuple(int(u) for u in dcl_unums),))
    t_src = t_src[:i] + seg.replace(t_hook, add + t_hook) + t_src[j:]
    teams = types.ModuleType('Teams')
    teams.__file__ = t_path
    exec(compile(t_src, t_path, 'exec'), teams.__dict__)
    sys.modules['Teams'] = teams
sys.argv = [src_path] + sys.argv[2:]
sys.path.insert(0, bin_dir)
exec(compile(src, src_path, 'exec'), {'__name__': '__main__', '__file__': src_path})
'''

# bin/Teams.py, Agent2d.__init__: defenseOrder = [2,3,4,5,6,7,8,11,9,10]; bin/Trainer.py,
# Trainer.getTeams puts 1 (the goalie) in front, and Trainer.run keeps
# defense_unums = sorted(_defenseOrder[:numDefense]): K defense NPCs are unums 1..K (K <= 7)
DEFENSE_ORDER = [1, 2, 3, 4, 5, 6, 7, 8, 11, 9, 10]


def defense_unums(k):
    return sorted(DEFENSE_ORDER[:k])


def cmd_record(a):
    if a.goalie:
        if a.defense_npcs not in (None, 1):
            raise SystemExit('--goalie is --defense-npcs 1')
        a.defense_npcs = 1
    k_def = a.defense_npcs or 0
    if not 0 <= k_def <= 3:
        raise SystemExit('--defense-npcs must be 0..3')
    out = os.path.abspath(a.out)
    os.makedirs(os.path.join(out, 'log'), exist_ok=True)
    hfo_bin = os.path.join(a.hfo, 'bin', 'HFO')
    hargs = ['--offense-agents', str(a.agents), '--headless', '--fullstate',
             '--frames-per-trial', str(a.frames_per_trial), '--seed', str(a.seed),
             '--port', str(a.port), '--log-dir', os.path.join(out, 'log'),
             '--trials', str(a.episodes)]
    if k_def:
        hargs += ['--defense-npcs', str(k_def)]
    dcl = defense_unums(k_def) if a.debug_logs else []
    env = dict(os.environ, HFO_RECORD_EXTRA_OPTIONS=NOISE_OFF, PYTHONUNBUFFERED='1',
               HFO_RECORD_DCL_UNUMS=' '.join(str(u) for u in dcl))
    cmd = [sys.executable, '-u', '-c', LAUNCHER, hfo_bin] + hargs
    meta = {'hfo': a.hfo, 'args': hargs, 'extra_server_options': NOISE_OFF,
            'seed': a.seed, 'mix': a.mix, 'agents': a.agents, 'goalie': k_def >= 1,
            'defense_npcs': k_def, 'defense_unums': defense_unums(k_def),
            'debug_server_logging_unums': dcl,
            'started': time.strftime('%Y-%m-%d %H:%M:%S')}
    with open(os.path.join(out, 'meta.json'), 'w') as fh:
        json.dump(meta, fh, indent=1)
    launcher_log = open(os.path.join(out, 'launcher.log'), 'w')
    srv = subprocess.Popen(cmd, cwd=out, env=env, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True, start_new_session=True)
    agents = []
    pat = re.compile(r'Waiting for player-controlled agent base_left-(\d+)')
    t0 = time.time()
    try:
        for line in srv.stdout:
            launcher_log.write(line)
            launcher_log.flush()
            m = pat.search(line)
            if m:
                k = int(m.group(1))
                alog = open(os.path.join(out, 'agent%d.log' % k), 'w')
                acmd = [sys.executable, os.path.realpath(__file__), 'agent', '--hfo', a.hfo,
                        '--port', str(a.port), '--index', str(k), '--out', out,
                        '--seed', str(a.seed), '--mix', a.mix]
                agents.append(subprocess.Popen(acmd, stdout=alog, stderr=subprocess.STDOUT))
                print('[record] agent %d started (%.1f s)' % (k, time.time() - t0), flush=True)
            if a.verbose and line.startswith('EndOfTrial'):
                sys.stdout.write(line)
        srv.wait()
    finally:
        if srv.poll() is None:
            os.killpg(srv.pid, signal.SIGTERM)
            srv.wait()
        for p in agents:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
    launcher_log.close()
    print('[record] done in %.1f s: %s' % (time.time() - t0, out), flush=True)


# ----------------------------------------------------------------------------------------
# parsing the server's logs

SHOW_RE = re.compile(r'^\(show (\d+) ')
BALL_RE = re.compile(r'\(\(b\) (\S+) (\S+) (\S+) (\S+)\)')
PLAYER_RE = re.compile(r'\(\((l|r) (\d+)\) (\d+) (\S+) (\S+) (\S+) (\S+) (\S+) (\S+) (\S+)'
                       r'(?: \S+ \S+)? \(v [hl] \S+\) \(s (\S+) (\S+) (\S+)(?: \S+)?\)')
RCL_RE = re.compile(r'^(\d+),(\d+)\t(.*)$')
RECV_RE = re.compile(r'^Recv (base_left|base_right)_(\d+): (.*)$')
BODY_CMDS = ('dash', 'turn', 'kick', 'tackle', 'catch', 'move')


def parse_rcg(path):
    """time -> (ball tuple, {(side, unum): player tuple}); the last show of each time."""
    shows = {}
    with open(path, errors='replace') as fh:
        for line in fh:
            m = SHOW_RE.match(line)
            if not m:
                continue
            t = int(m.group(1))
            b = BALL_RE.search(line)
            ball = tuple(float(x) for x in b.groups())
            players = {}
            for pm in PLAYER_RE.finditer(line):
                side, unum, _type, st = pm.group(1), int(pm.group(2)), pm.group(3), pm.group(4)
                state = int(st, 16) if st.startswith('0x') else int(st)
                if state == 0:
                    continue
                x, y, vx, vy, body, neck = (float(pm.group(i)) for i in range(5, 11))
                stam, eff, rec = float(pm.group(11)), float(pm.group(12)), float(pm.group(13))
                players[(side, unum)] = (x, y, vx, vy, body, stam, eff, rec, state)
            shows[t] = (ball, players)
    return shows


def split_cmds(msg):
    out, depth, start = [], 0, None
    for i, ch in enumerate(msg):
        if ch == '(':
            if depth == 0:
                start = i
            depth += 1
        elif ch == ')':
            depth -= 1
            if depth == 0 and start is not None:
                out.append(msg[start + 1:i])
    return out


def parse_rcl(path):
    """Commands per (time, team, unum) received in play (stoppage 0), and referee events."""
    cmds, referee = {}, {}
    with open(path, errors='replace') as fh:
        for line in fh:
            m = RCL_RE.match(line.rstrip('\n'))
            if not m:
                continue
            t, stop, msg = int(m.group(1)), int(m.group(2)), m.group(3)
            if stop != 0:
                continue
            r = RECV_RE.match(msg)
            if r:
                key = (t, 'l' if r.group(1) == 'base_left' else 'r', int(r.group(2)))
                for c in split_cmds(r.group(3)):
                    parts = c.split()
                    if parts and parts[0] in BODY_CMDS:
                        cmds.setdefault(key, []).append(parts)
                continue
            if msg.startswith('(referee '):
                referee.setdefault(t, []).append(msg[len('(referee '):-1])
    return cmds, referee


DCL_TIME_RE = re.compile(r'\(time (\d+)\)')
DCL_SELF_RE = re.compile(r'\(s ([lr]) (\d+) (\S+) (\S+) (\S+) (\S+) (\S+) (\S+) ')
DCL_BALL_RE = re.compile(r'\(b (\S+) (\S+)(?: (\S+) (\S+))? \(c "g(\d+)r(\d+)v(\d+)"\)\)')
DCL_TARGET_RE = re.compile(r'\(target-point (\S+) (\S+)\)')
DCL_MSG_RE = re.compile(r'\(message "([^"]*)"\)')
# parts of the .dcl message that name neck, view and attention actions, not the body's
# decision (agent2d: NeckScan…, NeckBall…, OffenseNeck…, InterceptNeck, IN:Default…,
# ViewNormal, AttCurSender…, AttBallNearest…, AttOff…)
DCL_NOT_BODY = ('Neck', 'OffenseNeck', 'InterceptNeck', 'IN:', 'View', 'Att')


def dcl_label(msg):
    parts = [x for x in msg.split('/') if x]
    return '/'.join(x for x in parts if not x.startswith(DCL_NOT_BODY))


def parse_dcl(path):
    """agent2d's --debug_server_logging file (librcsc DebugClient::toStr/write, format
    version 3): time -> what the player's world model held when it decided in that cycle.
    Coordinates in a .dcl are in the player's own frame (a right-side player has its goal at
    x = -52.5), here turned into the global frame of the .rcg. Returns (entries, duplicates)."""
    out, dup = {}, 0
    with open(path, errors='replace') as fh:
        for line in fh:
            if not line.startswith('%% debug ['):
                continue
            m = DCL_TIME_RE.search(line)
            if not m:
                continue
            t = int(m.group(1))
            e = {}
            sm = DCL_SELF_RE.search(line)
            sg = -1.0 if (sm and sm.group(1) == 'r') else 1.0
            if sm:
                x, y, vx, vy, body = (float(sm.group(i)) for i in range(3, 8))
                e['self'] = (sg * x, sg * y, sg * vx, sg * vy,
                             wrap(body + (180.0 if sg < 0 else 0.0)))
            bm = DCL_BALL_RE.search(line)
            if bm:
                e['ball'] = (sg * float(bm.group(1)), sg * float(bm.group(2)))
                e['bvel'] = None if bm.group(3) is None else \
                    (sg * float(bm.group(3)), sg * float(bm.group(4)))
                e['bcount'] = (int(bm.group(5)), int(bm.group(7)))   # pos count, vel count
            tm = DCL_TARGET_RE.search(line)
            if tm:
                e['target'] = (sg * float(tm.group(1)), sg * float(tm.group(2)))
            mm = DCL_MSG_RE.search(line)
            e['msg'] = mm.group(1) if mm else ''
            if t in out:
                dup += 1
            out[t] = e
    return out, dup


def status_of(events):
    for e in events:
        for name in ('GOAL', 'CAPTURED_BY_DEFENSE', 'OUT_OF_BOUNDS', 'OUT_OF_TIME'):
            if e.startswith(name):
                return name
    return 'IN_GAME'


def fmt(x, digits=7):
    if x == 0:
        return '0'
    return ('%.' + str(digits) + 'g') % x


def cmd_parse(a):
    import numpy as np
    run = os.path.abspath(a.run)
    meta = json.load(open(os.path.join(run, 'meta.json')))
    rcgs = sorted(glob.glob(os.path.join(run, 'log', '*.rcg')))
    rcls = sorted(glob.glob(os.path.join(run, 'log', '*.rcl')))
    if len(rcgs) != 1 or len(rcls) != 1:
        raise SystemExit('expected one .rcg and one .rcl in %s/log' % run)
    shows = parse_rcg(rcgs[0])
    cmds, referee = parse_rcl(rcls[0])
    agents = []
    for k in range(meta['agents']):
        d = np.load(os.path.join(run, 'agent%d.npz' % k))
        agents.append({k2: d[k2] for k2 in d.files})
    unums = [int(ag['unum']) for ag in agents]
    goalie = meta['goalie']
    src = a.src or os.path.basename(run.rstrip('/'))

    # episodes: HFORef resets the field in the cycle after a terminal one; the first
    # episode starts when the trainer switches to play_on (first IN_GAME referee message)
    times = sorted(shows)
    ref_times = sorted(referee)
    first = min(t for t in ref_times if any(e.startswith('IN_GAME') for e in referee[t]))
    # the reset state: the cycle where play_on begins is `first` (IN_GAME-U-1 sent there)
    ep_of, t_of = {}, {}
    ep, t_in = 1, 0
    last = max(times)
    status = {}
    for T in range(first, last + 1):
        if T not in shows:
            break
        ep_of[T], t_in_ep = ep, t_in
        t_of[T] = t_in
        st = status_of(referee.get(T, []))
        status[T] = st
        if st != 'IN_GAME':
            ep += 1
            t_in = 0
        else:
            t_in += 1
    n_ep_total = ep - 1

    # align each agent's steps to server cycles: after connecting, one step per cycle; a
    # step that returns a terminal status is followed by three hidden NOOP cycles
    # (HFOEnvironment::step). The first step's cycle is found by matching the decoded
    # self position to the .rcg.
    feat_at = []
    for k, ag in enumerate(agents):
        F = ag['features']
        n_team, n_opp = int(ag['n_team']), int(ag['n_opp'])
        key = ('l', unums[k])

        def err(i, T):
            if T not in shows or key not in shows[T][1]:
                return 1e9
            v = View(F[i], n_team, n_opp)
            p = shows[T][1][key]
            b = shows[T][0]
            return max(abs(v.x - p[0]), abs(v.y - p[1]), abs(v.bx - b[0]), abs(v.by - b[1]))

        # an anchor: a step in play whose decoded self and ball positions match exactly
        # one cycle of the log, and whose next steps follow it cycle by cycle
        play_times = [T for T in times if T >= first]
        best = None
        for i0 in range(0, min(400, len(F) - 6)):
            v = View(F[i0], n_team, n_opp)
            cands = []
            for T in play_times:
                p = shows[T][1].get(key)
                if p is None:
                    continue
                b = shows[T][0]
                if max(abs(v.x - p[0]), abs(v.y - p[1]), abs(v.bx - b[0]),
                       abs(v.by - b[1])) < 2e-3:
                    cands.append(T)
            if len(cands) != 1:
                continue
            T, ok = cands[0], True
            for i in range(i0, i0 + 5):
                st = int(ag['status'][i])
                T += 1 if st == IN_GAME else 4
                ok = ok and err(i + 1, T) < 2e-3
            if ok:
                best = (i0, cands[0])
                break
        if best is None:
            raise SystemExit('agent %d: cannot align its steps to the log' % k)
        i0, T0 = best
        m = {}
        T = T0
        for i in range(i0, len(F)):
            m[T] = i
            st = int(ag['status'][i])
            if st == SERVER_DOWN:
                break
            T += 1 if st == IN_GAME else 4
        # walk back before i0
        T = T0
        for i in range(i0 - 1, -1, -1):
            st = int(ag['status'][i])
            T -= 1 if st == IN_GAME else 4
            m[T] = i
        bad = sum(1 for T, i in m.items() if T in ep_of and err(i, T) > 2e-3)
        checked = sum(1 for T in m if T in ep_of)
        print('agent %d (unum %d): %d steps aligned, %d on play cycles, %d mismatches'
              % (k, unums[k], len(m), checked, bad))
        feat_at.append(m)

    players = [('p%d' % k, ('l', unums[k])) for k in range(len(agents))]
    if goalie:
        players.append(('g', ('r', 1)))
    nfs = [agents[k]['features'].shape[1] for k in range(len(agents))]
    # every defense NPC, goalie included, by uniform number: d0 = unum 1 (the goalie, also
    # `g`), d1 = unum 2, d2 = unum 3; with their .dcl where the recording has one
    n_def = meta.get('defense_npcs', 1 if goalie else 0)
    defenders = [('d%d' % i, ('r', u))
                 for i, u in enumerate(meta.get('defense_unums', defense_unums(n_def)))]
    dcls = {}
    for name, key in defenders:
        path = os.path.join(run, 'log', 'base_right-%d.dcl' % key[1])
        if os.path.exists(path):
            dcls[name], dup = parse_dcl(path)
            print('%s (unum %d): %d .dcl entries, %d cycles with more than one'
                  % (name, key[1], len(dcls[name]), dup))
    # players whose step outcomes go into `tags`: the agents, the goalie, field defenders
    tagged = players + [d for d in defenders if d[1] != ('r', 1)]

    header = ['src', 'ep', 't', 'cycle', 'status', 'tags', 'bx', 'by', 'bvx', 'bvy']
    for name, _ in players:
        header += [name + s for s in ('_x', '_y', '_vx', '_vy', '_body', '_stamina',
                                      '_effort', '_recovery', '_state', '_frozen', '_cmd',
                                      '_c1', '_c2')]
        if name != 'g':
            header += [name + '_req', name + '_r1', name + '_r2']
    for k in range(len(agents)):
        header += ['f%d_%d' % (k, j) for j in range(nfs[k])]
    for name, _ in defenders:
        header += [name + s for s in ('_x', '_y', '_vx', '_vy', '_body', '_stamina', '_state',
                                      '_cmd', '_c1', '_c2', '_label', '_tx', '_ty',
                                      '_wbx', '_wby', '_wbvx', '_wbvy', '_wbpc', '_wbvc')]

    tackle_cycles = 10
    with open(rcgs[0], errors='replace') as fh:
        for line in fh:
            m = re.search(r'\(tackle_cycles (\d+)\)', line)
            if m:
                tackle_cycles = int(m.group(1))
                break
    tackles = {key: sorted(T for (T, sd, un), c in cmds.items()
                           if (sd, un) == key and c[0][0] == 'tackle') for _, key in tagged}
    stats = {'episodes': 0, 'cycles': 0, 'statuses': {}, 'pcoll_cycles': 0,
             'bcoll_cycles': 0, 'double_kick_cycles': 0, 'double_kick_cmd_cycles': 0,
             'kicks': 0, 'tackles': 0, 'rows_with_features': [0] * len(agents)}
    eps_written = set()
    rows = []
    for T in sorted(ep_of):
        if ep_of[T] > n_ep_total or ep_of[T] < a.min_episode:
            continue
        ball, pl = shows[T]
        nxt = shows.get(T + 1)
        row = [src, ep_of[T], t_of[T], T, status[T]]
        tags = []
        # flags in the next show: what happened in the step T -> T+1
        kicks_ok, kick_cmds = 0, 0
        if nxt is not None and status[T] == 'IN_GAME':
            for name, key in tagged:
                if key in nxt[1]:
                    s = nxt[1][key][8]
                    if s & 0x800:
                        tags.append(name + ':pcoll')
                    if s & 0x400:
                        tags.append(name + ':bcoll')
                    if s & 0x10000:
                        tags.append(name + ':post')
        if nxt is not None:
            for name, key in tagged:
                c = cmds.get((T,) + key, [])
                if not c or key not in nxt[1]:
                    continue
                s = nxt[1][key][8]
                if c[0][0] == 'kick' and s & 0x4:
                    tags.append(name + ':kick_fault')
                if c[0][0] == 'tackle':
                    tags.append(name + (':tackle_fault' if s & 0x2000 else ':tackle_ok'))
                if len(c) > 1:
                    tags.append(name + ':multicmd')
        for name, key in tagged:
            c = cmds.get((T,) + key, [])
            if c and c[0][0] == 'kick':
                kick_cmds += 1
                if nxt is not None and key in nxt[1] and (nxt[1][key][8] & 0x6) == 0x2:
                    kicks_ok += 1
        if kick_cmds >= 2:
            tags.append('kick2cmd')
        if kicks_ok >= 2:
            tags.append('kick2')
        row.append(' '.join(tags))
        row += [fmt(x) for x in ball]
        for k, (name, key) in enumerate(players):
            p = pl.get(key)
            if p is None:
                row += [''] * 9
            else:
                row += [fmt(x) for x in p[:8]] + ['0x%x' % p[8]]
            # cycles the player stays frozen by its own last tackle (in any episode)
            import bisect
            tl = tackles[key]
            j = bisect.bisect_left(tl, T)
            row.append(str(max(0, tackle_cycles - (T - tl[j - 1])) if j > 0 else 0))
            c = cmds.get((T,) + key, [])
            if c:
                body = c[0]
                row += [body[0].upper()] + (body[1:] + ['', ''])[:2]
            else:
                row += ['NONE', '', '']
            if name != 'g':
                i = feat_at[k].get(T)
                if i is None:
                    row += ['', '', '']
                else:
                    act = int(agents[k]['action'][i])
                    pr = agents[k]['params'][i]
                    row += [ACT_NAME.get(act, str(act))] + [
                        '' if math.isnan(float(x)) else fmt(float(x), 9) for x in pr]
        for k in range(len(agents)):
            i = feat_at[k].get(T)
            if i is None:
                row += [''] * nfs[k]
            else:
                stats['rows_with_features'][k] += 1
                row += [fmt(float(x)) for x in agents[k]['features'][i]]
        for name, key in defenders:
            p = pl.get(key)
            if p is None:
                row += [''] * 7
            else:
                row += [fmt(x) for x in p[:6]] + ['0x%x' % p[8]]
            c = cmds.get((T,) + key, [])
            if c:
                # as logged; a foul tackle is (tackle DIR on): c2 = 'on'
                row += [c[0][0].upper()] + (c[0][1:] + ['', ''])[:2]
            else:
                row += ['NONE', '', '']
            e = dcls.get(name, {}).get(T)
            if e is None:
                row += [''] * 9
            else:
                row.append(dcl_label(e['msg']))
                row += [fmt(x) for x in e['target']] if 'target' in e else ['', '']
                row += [fmt(x) for x in e['ball']] if 'ball' in e else ['', '']
                row += [fmt(x) for x in e['bvel']] if e.get('bvel') else ['', '']
                row += [str(x) for x in e['bcount']] if 'bcount' in e else ['', '']
            defense_stats(stats, name, key, T, p, c, e, ball, status[T])
        rows.append(row)
        eps_written.add(ep_of[T])
        stats['cycles'] += 1
        if status[T] != 'IN_GAME':
            stats['statuses'][status[T]] = stats['statuses'].get(status[T], 0) + 1
        if any(t.endswith(':pcoll') for t in tags):
            stats['pcoll_cycles'] += 1
        if any(t.endswith(':bcoll') for t in tags):
            stats['bcoll_cycles'] += 1
        if 'kick2' in tags:
            stats['double_kick_cycles'] += 1
        if 'kick2cmd' in tags:
            stats['double_kick_cmd_cycles'] += 1
        for name, key in players:
            c = cmds.get((T,) + key, [])
            if c and c[0][0] == 'kick':
                stats['kicks'] += 1
            if c and c[0][0] == 'tackle':
                stats['tackles'] += 1
    stats['episodes'] = len(eps_written)
    if defenders:
        defense_stats_done(stats)
    with open(a.out, 'w', newline='') as fh:
        w = csv.writer(fh, lineterminator='\n')
        w.writerow(header)
        w.writerows(rows)
    stats['src'] = src
    print(json.dumps(stats))
    if a.stats:
        with open(a.stats, 'w') as fh:
            json.dump(stats, fh, indent=1)


def defense_stats(stats, name, key, T, p, c, e, ball, status):
    """Per defender: body command kinds, decision labels, and how far its world model (.dcl)
    is from the .rcg's truth in the same cycle. The .dcl rounds to 0.01 (DebugClient::toStr),
    so a difference above 0.011 is a real one."""
    d = stats.setdefault('defenders', {}).setdefault(name, {
        'unum': key[1], 'rows': 0, 'cmd': {}, 'labels': {}, 'rows_with_dcl': 0,
        'self_pos_err_max': 0.0, 'ball_pos_err_max': 0.0, 'ball_pos_off': 0,
        'ball_vel_known': 0, 'ball_vel_off': 0, 'ball_vel_off_zero': 0,
        'ball_vel_err_max': 0.0, 'ball_vel_off_ball_moving': 0, 'ball_moving': 0,
        'foul_tackles': 0})
    if p is None:
        return
    d['rows'] += 1
    kind = c[0][0].upper() if c else 'NONE'
    d['cmd'][kind] = d['cmd'].get(kind, 0) + 1
    if c and c[0][0] == 'tackle' and c[0][2:3] == ['on']:
        d['foul_tackles'] += 1
    if e is None:
        return
    d['rows_with_dcl'] += 1
    lab = re.sub(r'[-0-9.:|()]+.*$', '', dcl_label(e['msg']).split('/')[0]) or '(none)'
    d['labels'][lab] = d['labels'].get(lab, 0) + 1
    if 'self' in e:
        d['self_pos_err_max'] = max(d['self_pos_err_max'],
                                    math.hypot(e['self'][0] - p[0], e['self'][1] - p[1]))
    if 'ball' in e:
        err = math.hypot(e['ball'][0] - ball[0], e['ball'][1] - ball[1])
        d['ball_pos_err_max'] = max(d['ball_pos_err_max'], err)
        d['ball_pos_off'] += err > 0.011 * math.sqrt(2)
    moving = math.hypot(ball[2], ball[3]) > 0.011
    d['ball_moving'] += moving
    if e.get('bvel'):
        d['ball_vel_known'] += 1
        err = math.hypot(e['bvel'][0] - ball[2], e['bvel'][1] - ball[3])
        d['ball_vel_err_max'] = max(d['ball_vel_err_max'], err)
        if err > 0.011 * math.sqrt(2):
            d['ball_vel_off'] += 1
            d['ball_vel_off_ball_moving'] += moving
            d['ball_vel_off_zero'] += e['bvel'] == (0.0, 0.0) or e['bvel'] == (-0.0, -0.0)


def defense_stats_done(stats):
    for d in stats.get('defenders', {}).values():
        n = max(1, d['rows'])
        d['cmd_fraction'] = {k: round(v / n, 4) for k, v in sorted(d['cmd'].items())}
        d['ball_vel_off_fraction'] = round(d['ball_vel_off'] / max(1, d['ball_vel_known']), 4)
        d['labels'] = dict(sorted(d['labels'].items(), key=lambda kv: -kv[1]))


# ----------------------------------------------------------------------------------------
# subset: whole episodes for the tests

def cmd_subset(a):
    rng = random.Random(a.select_seed)
    eps = {}   # (src, ep) -> rows
    header = None
    for path in a.inputs:
        with open(path) as fh:
            r = csv.reader(fh)
            h = next(r)
            if header is None:
                header = h
            elif h != header:
                raise SystemExit('%s: columns differ' % path)
            for row in r:
                eps.setdefault((row[0], int(row[1])), []).append(row)
    ti = header.index('tags')
    si = header.index('status')
    tm = [i for i, h in enumerate(header) if h.startswith('f0_')][58:66]

    def has_tag(tag):
        return lambda rows: any(tag in r[ti].split() or any(
            t.endswith(':' + tag) for t in r[ti].split()) for r in rows)

    def hidden_mate(rows):
        return any(r[tm[0]] != '' and all(float(r[i]) == 0 for i in tm) for r in rows)

    def ends(st):
        return lambda rows: rows[-1][si] == st

    # (share of the rows, what an episode must show), filled in this order
    groups = [(0.2, has_tag('kick2')), (0.15, has_tag('pcoll')), (0.05, has_tag('tackle_ok')),
              (0.05, hidden_mate), (0.2, ends('GOAL')), (0.15, ends('CAPTURED_BY_DEFENSE')),
              (0.1, ends('OUT_OF_BOUNDS')), (0.1, ends('OUT_OF_TIME'))]
    # files with field defenders (d1_…): first the episodes where one kicks or tackles, or
    # believes a stale ball velocity, then the groups above
    dcols = [(header.index(h), header.index(h[:-4] + '_wbvx'))
             for h in header if re.fullmatch(r'd[1-9]_cmd', h)]
    if dcols:
        bvx, bvy = header.index('bvx'), header.index('bvy')

        def d_cmd(kind):
            return lambda rows: any(r[i] == kind for r in rows for i, _ in dcols)

        def stale(rows):
            return any(r[j] != '' and abs(float(r[j]) - float(r[bvx])) +
                       abs(float(r[j + 1]) - float(r[bvy])) > 0.1 for r in rows for _, j in dcols)
        groups = [(0.1, d_cmd('TACKLE')), (0.1, d_cmd('KICK')), (0.1, stale)] + groups
    keys = sorted(eps)
    rng.shuffle(keys)
    chosen, size = [], 0
    for share, pred in groups:
        n = 0
        for k in keys:
            L = len(eps[k])
            if k in chosen or L > a.max_episode_rows or n + L > share * a.max_rows \
                    or size + L > a.max_rows or not pred(eps[k]):
                continue
            chosen.append(k)
            n += L
            size += L
    for k in keys:
        L = len(eps[k])
        if k not in chosen and L <= a.max_episode_rows and size + L <= a.max_rows:
            chosen.append(k)
            size += L
    chosen.sort()
    with open(a.out, 'w', newline='') as fh:
        w = csv.writer(fh, lineterminator='\n')
        w.writerow(header)
        for k in chosen:
            w.writerows(eps[k])
    print('%d episodes, %d rows -> %s' % (len(chosen), size, a.out))


# ----------------------------------------------------------------------------------------

def main():
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest='cmd', required=True)
    r = sub.add_parser('record', help='run the server and the agents')
    r.add_argument('--hfo', default='/work/hfo-ext/HFO', help='HFO source/build root')
    r.add_argument('--out', required=True, help='recording folder (logs, agent step logs)')
    r.add_argument('--agents', type=int, default=2)
    r.add_argument('--defense-npcs', type=int, default=None,
                   help='agent2d defense NPCs, 0..3 (1: the goalie alone, 2: + one field '
                        'defender, 3: + two)')
    r.add_argument('--goalie', action='store_true', help='alias of --defense-npcs 1')
    r.add_argument('--no-debug-logs', dest='debug_logs', action='store_false',
                   help='do not give the defense NPCs --debug_server_logging (.dcl files)')
    r.add_argument('--episodes', type=int, default=100, help='HFO --trials')
    r.add_argument('--seed', type=int, default=1, help='server seed (also seeds the policies)')
    r.add_argument('--port', type=int, default=7100)
    r.add_argument('--frames-per-trial', type=int, default=500)
    r.add_argument('--mix', default=DEFAULT_MIX, help='episode modes and weights')
    r.add_argument('--verbose', action='store_true')
    g = sub.add_parser('agent', help='(internal) one agent process')
    g.add_argument('--hfo', required=True)
    g.add_argument('--port', type=int, required=True)
    g.add_argument('--index', type=int, required=True)
    g.add_argument('--out', required=True)
    g.add_argument('--seed', type=int, required=True)
    g.add_argument('--mix', default=DEFAULT_MIX)
    q = sub.add_parser('parse', help='logs -> per-cycle CSV')
    q.add_argument('--run', required=True)
    q.add_argument('--out', required=True)
    q.add_argument('--src', default='')
    q.add_argument('--stats', default='')
    q.add_argument('--min-episode', type=int, default=2,
                   help='first HFO episode to write (episode 1 starts before the agents run)')
    s = sub.add_parser('subset', help='whole episodes from parsed CSVs')
    s.add_argument('inputs', nargs='+')
    s.add_argument('--out', required=True)
    s.add_argument('--max-rows', type=int, default=1000)
    s.add_argument('--max-episode-rows', type=int, default=200)
    s.add_argument('--select-seed', type=int, default=1)
    a = p.parse_args()
    {'record': cmd_record, 'agent': cmd_agent, 'parse': cmd_parse, 'subset': cmd_subset}[a.cmd](a)


if __name__ == '__main__':
    main()
