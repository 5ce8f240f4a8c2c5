#!/usr/bin/env bash
# deploy/k8s/pamdp.yaml without a Kubernetes cluster:
#   schema:  every document is validated against the Kubernetes API's JSON schema (npm package
#            kubernetes-models 5, generated from the Kubernetes OpenAPI spec; YAML read as YAML 1.1,
#            as kubectl reads it): types, required fields, enums. Unknown fields are NOT caught
#            (those schemas allow additional properties).
#   the CLI: every container's command line (the learner's shell wrapper in both its branches) is
#            checked against the built pamdp: each --option must be one `pamdp SUBCOMMAND --help`
#            lists, each --config must name a file of deploy/configs (the image's /etc/pamdp/configs),
#            and the learner's --config with all its --set overrides must be accepted by
#            `pamdp train` (which refuses unknown keys and out-of-range values) and train 1 update.
#   wiring:  the key Secret is mounted read-only with mode 0400 wherever --curve-keys or
#            cluster.curve_keys_dir names it, and replay.shards equals the replay StatefulSet's replicas.
# Not tested: scheduling, volumes, DNS, networking, or any run on a real cluster (the container
# cluster of tests/system/container_test.sh runs the same image and options with Docker).
# The npm packages go to PAMDP_NPM_DIR (default ~/.cache/pamdp-k8s-validate). Skips (77) without
# node/npm or when they cannot be installed.
# Usage: tests/system/k8s_manifest_test.sh PATH/TO/pamdp SOURCE_DIR
set -euo pipefail
bin=$(readlink -f "${1:?path to pamdp}")
src=$(cd "${2:?source dir}" && pwd)
test_name=k8s_manifest_test
skip() {
  echo "$test_name: SKIP: $*"
  exit 77
}
command -v node >/dev/null && command -v npm >/dev/null || skip "no node/npm (Debian: apt-get install nodejs npm)"
npm_dir=${PAMDP_NPM_DIR:-$HOME/.cache/pamdp-k8s-validate}
if [[ ! -f $npm_dir/node_modules/kubernetes-models/package.json || ! -f $npm_dir/node_modules/yaml/package.json ]]; then
  mkdir -p "$npm_dir"
  (cd "$npm_dir" && [[ -f package.json ]] || echo '{"private": true}' >package.json)
  (cd "$npm_dir" && npm install --no-audit --no-fund --silent kubernetes-models@5 yaml@2) >/dev/null 2>&1 ||
    skip "cannot install kubernetes-models and yaml from npm into $npm_dir"
fi
work=$(mktemp -d "/tmp/pamdp-$test_name.XXXXXX")
trap 'rm -rf "$work"' EXIT
fail() {
  echo "$test_name: FAIL: $*" >&2
  exit 1
}

# Schema validation; prints one line per container: NAME<TAB>argv as JSON (the learner's shell
# command is expanded for both branches of its `if`), and the wiring facts.
cat >"$npm_dir/check.mjs" <<'EOF'
import { readFileSync } from "node:fs";
import { parseAllDocuments } from "yaml";
import * as k8s from "kubernetes-models";
const groups = { v1: k8s.v1, "apps/v1": k8s.apps.v1 };
const docs = parseAllDocuments(readFileSync(process.argv[2], "utf8"), { version: "1.1" });
let failures = 0;
for (const doc of docs) {
  if (doc.errors.length) { console.error(`YAML: ${doc.errors[0].message}`); failures++; continue; }
  const obj = doc.toJS();
  const Model = groups[obj.apiVersion]?.[obj.kind];
  if (!Model) { console.error(`unknown kind ${obj.apiVersion} ${obj.kind}`); failures++; continue; }
  try { new Model(obj).validate(); } catch (e) { console.error(`${obj.kind} ${obj.metadata?.name}: ${e.message}`); failures++; continue; }
  const pod = obj.spec?.template?.spec;
  if (!pod) continue;
  const secretVolumes = (pod.volumes ?? []).filter((v) => v.secret);
  for (const c of pod.containers) {
    const argv = [...(c.command ?? []), ...(c.args ?? [])];
    const mounts = (c.volumeMounts ?? []).map((m) => {
      const v = secretVolumes.find((s) => s.name === m.name);
      return v ? { path: m.mountPath, readOnly: !!m.readOnly, mode: v.secret.defaultMode } : null;
    }).filter(Boolean);
    console.log(JSON.stringify({ name: `${obj.metadata.name}/${c.name}`, replicas: obj.spec.replicas, argv, mounts }));
  }
}
process.exit(failures ? 1 : 0);
EOF
(cd "$npm_dir" && node check.mjs "$src/deploy/k8s/pamdp.yaml") >"$work/containers.jsonl" 2>"$work/schema.err" ||
  fail "the Kubernetes schema refuses deploy/k8s/pamdp.yaml: $(cat "$work/schema.err")"
echo "schema: $(grep -c '^---' "$src/deploy/k8s/pamdp.yaml" | awk '{ print $1 + 1 }') documents valid; $(wc -l <"$work/containers.jsonl") containers"

# The argv of each container as lines of words; the learner's `sh -c` wrapper split into its two
# command lines (new run and --resume), with ${start} expanded.
"$bin" keygen --dir "$work/keys" >/dev/null
replay_replicas=""
shards_set=""
checked=0
while read -r line; do
  name=$(node -e 'console.log(JSON.parse(process.argv[1]).name)' "$line")
  mapfile -t argv < <(node -e 'for (const a of JSON.parse(process.argv[1]).argv) console.log(a)' "$line")
  mounts=$(node -e 'console.log(JSON.stringify(JSON.parse(process.argv[1]).mounts))' "$line")
  replicas=$(node -e 'console.log(JSON.parse(process.argv[1]).replicas ?? "")' "$line")
  commands=()
  if [[ ${argv[0]} == /bin/sh && ${argv[1]} == -c ]]; then
    script=${argv[2]}
    for branch in 1 2; do
      start=$(grep -o 'start="[^"]*"' <<<"$script" | sed -n "${branch}p" | sed 's/^start="//; s/"$//')
      [[ -n $start ]] || fail "$name: no start=\"…\" in its shell wrapper"
      cmd=$(grep -o 'exec pamdp .*' <<<"$script" | sed "s|\$start|$start|; s|^exec pamdp ||")
      commands+=("$cmd")
    done
  else
    [[ ${argv[0]} != pamdp ]] || argv=("${argv[@]:1}")
    commands+=("${argv[*]}")
  fi
  for cmd in "${commands[@]}"; do
    read -ra words <<<"$cmd"
    sub=${words[0]}
    help=$("$bin" "$sub" --help 2>&1) || fail "$name: pamdp $sub --help failed: $help"
    sets=()
    config=""
    for ((i = 1; i < ${#words[@]}; i++)); do
      w=${words[i]}
      case $w in
        --*)
          grep -qE -- "(^|[ ,])$w([ ,]|$)" <<<"$help" || fail "$name: pamdp $sub has no option $w"
          ;;
      esac
      case $w in
        --set) sets+=("${words[i + 1]}") ;;
        --config) config=${words[i + 1]} ;;
        --curve-keys) [[ $mounts == *"\"path\":\"${words[i + 1]}\",\"readOnly\":true,\"mode\":256"* ]] ||
          fail "$name: --curve-keys ${words[i + 1]} is not a read-only Secret volume with mode 0400 ($mounts)" ;;
      esac
    done
    if [[ $sub == learner ]]; then
      for s in "${sets[@]}"; do
        [[ $s != cluster.curve_keys_dir=* ]] || [[ $mounts == *"\"path\":\"${s#*=}\",\"readOnly\":true,\"mode\":256"* ]] ||
          fail "$name: $s is not a read-only Secret volume with mode 0400 ($mounts)"
        [[ $s != replay.shards=* ]] || shards_set=${s#*=}
      done
      if [[ -n $config ]]; then
        local_config=$src/deploy/configs/${config#/etc/pamdp/configs/}
        [[ $config == /etc/pamdp/configs/* && -f $local_config ]] ||
          fail "$name: --config $config is not a file of deploy/configs (the image's /etc/pamdp/configs)"
        train_sets=()
        for s in "${sets[@]}"; do
          [[ $s == cluster.curve_keys_dir=* ]] && s=cluster.curve_keys_dir=$work/keys
          train_sets+=(--set "$s")
        done
        out=$(timeout 120 "$bin" train --config "$local_config" "${train_sets[@]}" --set train.max_updates=1 \
          --set replay.warmup=100 --set train.eval_every_updates=0 --run-dir "$work/train-$checked" --quiet 2>&1) ||
          fail "$name: pamdp train refuses the learner's config and overrides: $(tail -n 3 <<<"$out")"
      fi
    fi
    checked=$((checked + 1))
  done
  [[ $name != pamdp-replay/* ]] || replay_replicas=$replicas
done <"$work/containers.jsonl"
[[ -n $shards_set && $shards_set == "$replay_replicas" ]] ||
  fail "the learner's replay.shards ($shards_set) differs from the pamdp-replay replicas ($replay_replicas)"
echo "cli: $checked command lines match pamdp's options and config keys; replay.shards $shards_set = replicas; key Secret mounted 0400 read-only"
echo "$test_name: PASS"
