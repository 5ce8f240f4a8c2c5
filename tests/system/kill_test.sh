#!/usr/bin/env bash
# Killed processes on a local cluster (1 learner, 2 replay shards, 2 actors as processes on
# loopback, toy ReachStop task, small warm-up). Every assertion reads the processes' /metrics
# (or the run directory's metrics.csv and checkpoint), not their logs:
#   actor:   kill -9 one actor; the learner keeps updating and counts 1 actor; a restarted actor
#            rejoins (2 actors) and acts with weights at least as new as the learner's when it started.
#   shard:   kill -9 one shard (it writes its snapshot every second); the learner keeps updating
#            from the other and counts 1 shard; the shard restarted on new ports with the same
#            snapshot restored every row of it (pamdp_replay_restored_transitions), holds data it
#            did not insert (size > its own inserts) and is counted again.
#   learner: kill -9 the learner, restart it with --resume on the same ports; updates and episodes
#            start from the checkpoint (>= its counters), and the SAME shard and actor processes
#            reconnect (2 shards, 2 actors, updates increase).
#   SIGTERM: the learner stops with status 0, leaving checkpoint.ckpt; --resume starts from it.
# Prints one line per scenario with its counts. Usage: tests/system/kill_test.sh PATH/TO/pamdp SOURCE_DIR
set -euo pipefail
bin=${1:?path to pamdp}
src=$(cd "${2:?source dir}" && pwd)
test_name=kill_test
# shellcheck source=tests/system/cluster_lib.sh
source "$src/tests/system/cluster_lib.sh"
faults=0

start_learner learner --config "$src/deploy/configs/reach_stop.toml" --run-dir "$work/run" \
  --set cluster.learner_bind=tcp://127.0.0.1:0 --set cluster.weights_bind=tcp://127.0.0.1:0
start_shard 0 --snapshot "$work/shard-0.replay" --snapshot-every 1
start_shard 1 --snapshot "$work/shard-1.replay" --snapshot-every 1
start_actor 0 actor-0
start_actor 1 actor-1
wait_for 30 "the cluster did not form (shards $(peers replay), actors $(peers actor))" \
  '[[ $(peers replay) == 2 && $(peers actor) == 2 ]]'
wait_for 40 "no updates" 'gt "$(updates)" 100'
echo "cluster up at $(since): updates $(updates), shards $(peers replay), actors $(peers actor)"

# --- actor ------------------------------------------------------------------------------------
kill -KILL "${pid[actor0]}"
wait "${pid[actor0]}" 2>/dev/null || true
faults=$((faults + 1))
wait_for 20 "the learner still counts 2 actors after kill -9" '[[ $(peers actor) == 1 ]]'
updates_grow "actor killed" 100
version_at_restart=$(metric "$lurl" pamdp_learner_weights_version)
start_actor 0 actor-0b
wait_for 20 "the restarted actor was not counted (actors $(peers actor))" '[[ $(peers actor) == 2 ]]'
wait_for 20 "the restarted actor has weights version $(metric "${aurl[0]}" pamdp_actor_weights_version), the learner was at $version_at_restart" \
  'ge "$(metric "${aurl[0]}" pamdp_actor_weights_version)" "$version_at_restart"'
echo "actor: kill -9 -> learner went on (updates $(updates)); restarted actor joined with weights v$(metric "${aurl[0]}" pamdp_actor_weights_version) (learner v$version_at_restart at its start, now v$(metric "$lurl" pamdp_learner_weights_version)) at $(since)"

# --- replay shard -----------------------------------------------------------------------------
wait_for 20 "shard 1 wrote no snapshot" '[[ -s $work/shard-1.replay ]]'
sleep_until_snapshot=$(stat -c %Y "$work/shard-1.replay")
size_before=$(metric "${surl[1]}" pamdp_replay_size_transitions)
kill -KILL "${pid[shard1]}"
wait "${pid[shard1]}" 2>/dev/null || true
faults=$((faults + 1))
snapshot_bytes=$(stat -c %s "$work/shard-1.replay")
wait_for 20 "the learner still counts 2 shards after kill -9" '[[ $(peers replay) == 1 ]]'
updates_grow "shard killed" 100
start_shard 1 --snapshot "$work/shard-1.replay" --snapshot-every 1
wait_for 20 "the restarted shard did not take its config" 'gt "$(metric "${surl[1]}" pamdp_replay_capacity_transitions)" 0'
# Both from one scrape: actors insert into the new shard as soon as they hear of it. (Size minus
# inserts is not the restored count: once the ring is full, inserts overwrite restored rows.)
scrape=$(curl -sf --max-time 2 "${surl[1]}" || true)
size_after=$(awk '$1 == "pamdp_replay_size_transitions" { print $2 }' <<<"$scrape")
inserted_after=$(awk '$1 == "pamdp_replay_transitions_inserted_total" { print $2 }' <<<"$scrape")
restored=$(awk '$1 == "pamdp_replay_restored_transitions" { print $2 }' <<<"$scrape")
[[ -n $size_after && -n $inserted_after && -n $restored ]] || fail "the restarted shard's /metrics did not answer"
restored=${restored%.*}
((restored > 0)) || fail "the restarted shard restored nothing from its snapshot (it holds $size_after transitions, $inserted_after of them its own inserts)"
((${size_after%.*} > ${inserted_after%.*})) ||
  fail "the restarted shard holds $size_after transitions, all of them its own inserts ($inserted_after)"
# The snapshot's row count (replay/replay_snapshot.cpp: a 40-byte header, rows of 2 obs + action +
# 3 floats, an 8-byte checksum), with the widths the shard logged.
widths=$(grep -o 'widths [0-9]*/[0-9]*' "$work/logs/shard-1.log" | head -n 1 | grep -o '[0-9]*/[0-9]*')
snapshot_rows=$(((snapshot_bytes - 48) / ((2 * ${widths%/*} + ${widths#*/} + 3) * 4)))
((restored == snapshot_rows)) || fail "the restarted shard restored $restored transitions, its snapshot held $snapshot_rows"
wait_for 20 "the restarted shard was not counted (shards $(peers replay))" '[[ $(peers replay) == 2 ]]'
updates_grow "shard restarted" 100
echo "shard: kill -9 with $size_before transitions (snapshot $snapshot_bytes bytes, mtime $sleep_until_snapshot) -> learner went on; restarted shard restored $restored of the snapshot's $snapshot_rows transitions (size $size_after, own inserts $inserted_after), 2 shards again at $(since)"

# --- learner: kill -9, --resume on the same ports ----------------------------------------------
wait_for 20 "no checkpoint" '[[ -s $work/run/checkpoint.ckpt ]]'
actor1_version=$(metric "${aurl[1]}" pamdp_actor_weights_version)
# Kill it when metrics.csv has a row past the checkpoint (it logs every 0.5 s and checkpoints
# every 1 s), so that the resumed learner finds rows its predecessor wrote after the checkpoint.
# A checkpoint written between the look and the kill only makes the check below weaker.
for _ in $(seq 40); do
  cp "$work/run/checkpoint.ckpt" "$work/probe.ckpt"
  (cd "$work" && flatc --json --strict-json --raw-binary "$src/schemas/checkpoint.fbs" -- probe.ckpt)
  probe_updates=$(grep -o '"updates": *[0-9]*' "$work/probe.json" | grep -o '[0-9]*$' || echo 0)
  last_row_updates=$(tail -n 1 "$work/run/metrics.csv" | cut -d, -f2)
  if [[ $last_row_updates =~ ^[0-9]+$ ]] && ((last_row_updates > probe_updates)) &&
    cmp -s "$work/run/checkpoint.ckpt" "$work/probe.ckpt"; then
    break
  fi
  sleep 0.05
done
kill -KILL "${pid[learner]}"
wait "${pid[learner]}" 2>/dev/null || true
faults=$((faults + 1))
cp "$work/run/checkpoint.ckpt" "$work/killed.ckpt"
# The counters the resumed learner must start from, read from the checkpoint with flatc.
(cd "$work" && flatc --json --strict-json --raw-binary "$src/schemas/checkpoint.fbs" -- killed.ckpt)
ck_updates=$(grep -o '"updates": *[0-9]*' "$work/killed.json" | grep -o '[0-9]*$' || echo 0)
ck_episodes=$(grep -o '"episodes": *[0-9]*' "$work/killed.json" | grep -o '[0-9]*$' || echo 0)
ck_version=$(grep -o '"weights_version": *[0-9]*' "$work/killed.json" | grep -o '[0-9]*$' || echo 0)
((ck_updates > 0)) || fail "the checkpoint holds no updates"
((ck_version > 0)) || fail "the checkpoint holds no weights version"
old_join=$join
start_learner learner-resumed --resume "$work/run" \
  --set "cluster.learner_bind=$old_join" --set "cluster.weights_bind=$weights"
[[ $join == "$old_join" ]] || fail "the resumed learner is at $join, not $old_join"
wait_for 30 "the resumed learner did not update" 'gt "$(updates)" 0'
first=$(updates)
ge "$first" "$ck_updates" || fail "the resumed learner is at $first updates, the checkpoint had $ck_updates"
wait_for 30 "the same shards and actors did not reconnect (shards $(peers replay), actors $(peers actor))" \
  '[[ $(peers replay) == 2 && $(peers actor) == 2 ]]'
for p in shard0 shard1 actor0 actor1; do
  kill -0 "${pid[$p]}" 2>/dev/null || fail "$p exited while the learner was away"
done
updates_grow "learner resumed" 200
# Only the resumed learner can have sent the actor other weights since.
# The resumed learner numbers its weights on from the checkpoint's version (versions never go
# back, so episodes.csv's weights_version stays monotonic across a restart).
wait_for 20 "actor 1 got no weights from the resumed learner (still v$actor1_version, checkpoint v$ck_version)" \
  'gt "$(metric "${aurl[1]}" pamdp_actor_weights_version)" "$ck_version"'
# metrics.csv: the resumed learner's rows go on from the checkpoint's counters.
column() {
  awk -F, -v name="$1" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == name) c = i } END { if (c) print $c }' "$work/run/metrics.csv"
}
wait_for 10 "metrics.csv has no row from the resumed learner" 'ge "$(column updates)" "$first"'
csv_episodes=$(column episodes)
ge "$csv_episodes" "$ck_episodes" || fail "episodes $csv_episodes after resume, the checkpoint had $ck_episodes"
# The updates after the checkpoint are redone and logged once: metrics.csv's updates never go
# back. The episodes the actors played meanwhile stay logged, and the resumed learner numbers its
# episodes after them: episodes.csv counts 1, 2, 3, ... with no number twice, and its clock
# (wall_seconds) goes on from the last of them.
updates_back=$(awk -F, 'NR > 2 && $2 < prev { print NR ": " prev " -> " $2; exit } NR > 1 { prev = $2 }' "$work/run/metrics.csv")
[[ -z $updates_back ]] || fail "metrics.csv's updates go back after the resume (line $updates_back)"
episodes_off=$(awk -F, 'NR > 1 && $1 != NR - 1 { print NR ": episode " $1; exit }' "$work/run/episodes.csv")
[[ -z $episodes_off ]] || fail "episodes.csv is not numbered 1, 2, 3, ... after the resume (line $episodes_off)"
clock_back=$(awk -F, 'NR > 2 && $2 < prev { print NR ": " prev " -> " $2; exit } NR > 1 { prev = $2 }' "$work/run/episodes.csv")
[[ -z $clock_back ]] || fail "episodes.csv's wall_seconds go back after the resume (line $clock_back)"
echo "learner: kill -9 at checkpoint updates $ck_updates, episodes $ck_episodes, weights v$ck_version -> resumed at $first updates, episodes $csv_episodes, same 2 shards + 2 actors back (actor 1 weights v$actor1_version -> v$(metric "${aurl[1]}" pamdp_actor_weights_version)), updates now $(updates) at $(since)"

# --- SIGTERM: a resumable run directory ---------------------------------------------------------
kill -TERM "${pid[learner]}"
status=0
wait "${pid[learner]}" || status=$?
((status == 0)) || fail "the learner exited with status $status on SIGTERM"
faults=$((faults + 1))
[[ -s $work/run/checkpoint.ckpt ]] || fail "no checkpoint.ckpt after SIGTERM"
(cd "$work" && cp run/checkpoint.ckpt term.ckpt && flatc --json --strict-json --raw-binary "$src/schemas/checkpoint.fbs" -- term.ckpt)
term_updates=$(grep -o '"updates": *[0-9]*' "$work/term.json" | grep -o '[0-9]*$')
ge "$term_updates" "$first" || fail "the SIGTERM checkpoint has $term_updates updates, fewer than the run had"
start_learner learner-term-resumed --resume "$work/run" \
  --set "cluster.learner_bind=$old_join" --set "cluster.weights_bind=$weights"
wait_for 30 "the learner resumed after SIGTERM did not update" 'gt "$(updates)" 0'
ge "$(updates)" "$term_updates" || fail "resumed after SIGTERM at $(updates) updates, the checkpoint had $term_updates"
echo "SIGTERM: exit 0, checkpoint at $term_updates updates; --resume went on at $(updates) updates at $(since)"
echo "kill_test: OK: $faults faults injected (3 kill -9, 1 SIGTERM), 0 processes failed to rejoin, in $(since)"
