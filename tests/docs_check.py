#!/usr/bin/env python3
"""The documentation as a reader meets it. Fails (exit 1), naming file and line, when:

  links     a relative link or image in README.md, docs/**/*.md or models/README.md names a file
            that does not exist, or an anchor (#...) that no heading of the target makes
            (GitHub's rule: lower case, punctuation dropped, spaces to hyphens, -1, -2 for repeats);
  commands  a `build/bin/pamdp ...` line in a shell code block of README.md or docs/*.md names a
            subcommand, or an --option, that the built pamdp's `--help` does not list, or a
            `--config`/`--checkpoint` file of the repository that does not exist; a
            `deploy/local-cluster.sh ...` line an option its --help does not list;
  sessions  the word "session(s)" appears, except as HFO's own agent session ("agent session").

Usage: tests/docs_check.py --bin build/bin/pamdp --root .   (tests/CMakeLists.txt: docs_check)
"""
import argparse
import re
import shlex
import subprocess
import sys
from pathlib import Path

LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
FENCE = re.compile(r"^\s*```(\w*)")
SESSION = re.compile(r"\bsessions?\b", re.IGNORECASE)
ALLOWED_SESSION = re.compile(r"\bagent sessions?\b", re.IGNORECASE)


def doc_files(root):
    files = [root / "README.md", root / "models" / "README.md"]
    files += sorted((root / "docs").rglob("*.md"))
    return [f for f in files if f.exists()]


def slug(heading):
    """GitHub's anchor for a heading: inline code and links reduced to their text first."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)
    text = text.replace("`", "").strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)  # \w keeps letters of any script, digits and _
    return text.replace(" ", "-")


def anchors(path, cache={}):
    if path not in cache:
        seen, out, in_code = {}, set(), False
        for line in path.read_text(encoding="utf-8").splitlines():
            if FENCE.match(line):
                in_code = not in_code
                continue
            m = None if in_code else HEADING.match(line)
            if m:
                s = slug(m.group(2))
                n = seen.get(s, 0)
                out.add(s if n == 0 else f"{s}-{n}")
                seen[s] = n + 1
            for a in re.findall(r'<a (?:name|id)="([^"]+)"', line):
                out.add(a)
        cache[path] = out
    return cache[path]


def lines_outside_code(path):
    in_code = False
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        if FENCE.match(line):
            in_code = not in_code
            continue
        if not in_code:
            yield number, line


def check_links(root, files, errors):
    for f in files:
        for number, line in lines_outside_code(f):
            for target in LINK.findall(re.sub(r"`[^`]*`", "", line)):
                if re.match(r"^[a-z][a-z0-9+.-]*:", target):  # http:, https:, mailto:
                    continue
                file_part, _, anchor = target.partition("#")
                dest = (f.parent / file_part).resolve() if file_part else f
                where = f"{f.relative_to(root)}:{number}"
                if not dest.exists():
                    errors.append(f"{where}: link to '{target}': no file {dest.relative_to(root.resolve()) if dest.is_relative_to(root.resolve()) else dest}")
                    continue
                if anchor and dest.suffix == ".md" and anchor not in anchors(dest):
                    errors.append(f"{where}: link to '{target}': no heading makes the anchor #{anchor} in {dest.name}")


def shell_commands(path):
    """(line number, command) for each command line of the file's sh/bash/shell code blocks,
    continuation lines joined and comments dropped."""
    in_code, lang, pending, start = False, "", "", 0
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        m = FENCE.match(line)
        if m:
            in_code, lang = (not in_code), m.group(1)
            continue
        if not in_code or lang not in ("sh", "bash", "shell", "console", ""):
            continue
        if not pending:
            start = number
        pending += line.rstrip()
        if pending.endswith("\\"):
            pending = pending[:-1] + " "
            continue
        yield start, pending
        pending = ""


def words_of(command):
    try:
        lexer = shlex.shlex(command, posix=True, punctuation_chars=";&|<>")
        lexer.whitespace_split = True
        lexer.commenters = "#"
        return list(lexer)
    except ValueError:
        return None


def help_options(argv, cache={}):
    key = tuple(argv)
    if key not in cache:
        r = subprocess.run(argv + ["--help"], capture_output=True, text=True, timeout=30)
        text = r.stdout + r.stderr
        cache[key] = (r.returncode, set(re.findall(r"(?<![\w-])(--[a-zA-Z][\w-]*)", text)), text)
    return cache[key]


def check_commands(root, pamdp, errors):
    files = [root / "README.md"] + sorted((root / "docs").glob("*.md"))
    rc, _, top_help = help_options([pamdp])
    subcommands = subcommands_of(top_help)
    if not subcommands:
        errors.append(f"`pamdp --help` lists no subcommands (exit {rc}): is {pamdp} the built pamdp?")
        return
    checked = 0
    for f in files:
        for number, command in shell_commands(f):
            words = words_of(command)
            if words is None:
                continue
            where = f"{f.relative_to(root)}:{number}"
            # One line may chain several commands (&&, ;, |, $(...)): check each pamdp call in it.
            for i, w in enumerate(words):
                if re.search(r"(^|/)build/bin/pamdp$", w):
                    checked += check_pamdp_call(root, pamdp, subcommands, words[i + 1 :], where, errors)
                elif w == "deploy/local-cluster.sh":
                    checked += check_script_call(root, root / w, words[i + 1 :], where, errors)
    if checked == 0:
        errors.append("README.md: no `build/bin/pamdp` command found in its code blocks (the check would test nothing)")


def subcommands_of(help_text):
    """The names CLI11's --help lists under its "Subcommands:" heading."""
    parts = re.split(r"^Subcommands:\s*$", help_text, maxsplit=1, flags=re.MULTILINE | re.IGNORECASE)
    if len(parts) < 2:
        return set()
    names = set()
    for line in parts[1].splitlines():
        if line and not line[0].isspace():
            break  # the next heading or the epilogue
        m = re.match(r"^\s{2}([a-z][\w-]*)(\s|$)", line)
        if m:
            names.add(m.group(1))
    return names


def call_words(words):
    out = []
    for w in words:
        if w in (";", "&", "&&", "|", "||", ">", "<", ">>", "2>", ")") or w.startswith("$(") or w.startswith(")"):
            break
        out.append(w)
    return out


def check_pamdp_call(root, pamdp, subcommands, words, where, errors):
    words = call_words(words)
    if not words or words[0].startswith("-"):
        return 1  # `pamdp --help` and the like
    sub = words[0]
    if sub not in subcommands:
        errors.append(f"{where}: `pamdp {sub}`: no such subcommand (pamdp --help lists {', '.join(sorted(subcommands))})")
        return 1
    argv = [pamdp, sub]
    rest = words[1:]
    rc, options, text = help_options(argv)
    nested = subcommands_of(text)
    if nested:
        if not rest or rest[0] not in nested:
            errors.append(f"{where}: `pamdp {sub} {rest[0] if rest else ''}`: `pamdp {sub}` takes one of {', '.join(sorted(nested))}")
            return 1
        argv.append(rest[0])
        rest = rest[1:]
        rc, options, text = help_options(argv)
    if rc != 0:
        errors.append(f"{where}: `{' '.join(Path(a).name if a == pamdp else a for a in argv)} --help` exits {rc}")
        return 1
    name = " ".join(["pamdp"] + argv[1:])
    for j, w in enumerate(rest):
        if not w.startswith("--"):
            continue
        option = w.split("=", 1)[0]
        if option not in options:
            errors.append(f"{where}: `{name} {option}`: `{name} --help` lists no such option")
            continue
        value = w.split("=", 1)[1] if "=" in w else (rest[j + 1] if j + 1 < len(rest) else "")
        if option in ("--config", "--checkpoint") and re.match(r"^(deploy|models)/[\w./-]+$", value):
            if not (root / value).exists():
                errors.append(f"{where}: `{name} {option} {value}`: no such file in the repository")
    return 1


def check_script_call(root, script, words, where, errors):
    r = subprocess.run(["bash", str(script), "--help"], capture_output=True, text=True, timeout=30)
    options = set(re.findall(r"(?<![\w-])(--[a-zA-Z][\w-]*)", r.stdout + r.stderr))
    for j, w in enumerate(call_words(words)):
        option = w.split("=", 1)[0]
        if option.startswith("--") and option not in options:
            errors.append(f"{where}: `deploy/local-cluster.sh {option}`: its --help lists no such option")
        if option == "--config" and j + 1 < len(words) and not (root / words[j + 1]).exists():
            errors.append(f"{where}: `deploy/local-cluster.sh --config {words[j + 1]}`: no such file")
    return 0


def check_sessions(root, files, errors):
    for f in files:
        for number, line in enumerate(f.read_text(encoding="utf-8").splitlines(), 1):
            if SESSION.search(ALLOWED_SESSION.sub("", line)):
                errors.append(f"{f.relative_to(root)}:{number}: speaks of a session (say the date, commit, preset or key): {line.strip()[:100]}")


def check(root, pamdp):
    files = doc_files(root)
    errors = []
    check_links(root, files, errors)
    check_commands(root, pamdp, errors)
    check_sessions(root, files, errors)
    return files, errors


def self_test(pamdp):
    """The check must catch what it is for: a tree with one of each fault, and a clean one."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "docs").mkdir()
        (root / "deploy" / "configs").mkdir(parents=True)
        (root / "deploy" / "configs" / "fast.toml").write_text("")
        (root / "docs" / "page.md").write_text("# A page\n\n## Two words\n\nHFO serves one agent session.\n")
        good = (
            "# pamdp\n\n[page](docs/page.md#two-words)\n\n```sh\n"
            "build/bin/pamdp eval --episodes 10 --seed 1 --json   # a comment --not-an-option\n"
            "build/bin/pamdp sim trace --init S.json --actions A.csv \\\n    --no-noise\n"
            "build/bin/pamdp train --config deploy/configs/fast.toml\n```\n"
        )
        (root / "README.md").write_text(good)
        _, errors = check(root, pamdp)
        assert not errors, f"self-test: a clean tree reported {errors}"
        faults = {
            "no file": "[gone](docs/missing.md)",
            "no heading makes the anchor": "[bad anchor](docs/page.md#three-words)",
            "lists no such option": "```sh\nbuild/bin/pamdp eval --episodez 10\n```",
            "no such subcommand": "```sh\nbuild/bin/pamdp evaluate --episodes 10\n```",
            "no such file in the repository": "```sh\nbuild/bin/pamdp train --config deploy/configs/gone.toml\n```",
            "speaks of a session": "Measured in the third session.",
        }
        for expected, text in faults.items():
            (root / "README.md").write_text(good + "\n" + text + "\n")
            _, errors = check(root, pamdp)
            assert any(expected in e for e in errors), f"self-test: '{text}' was not reported as '{expected}': {errors}"
    print(f"docs_check: self-test: a clean tree passes, {len(faults)} faults caught")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--bin", required=True, help="the built pamdp")
    parser.add_argument("--root", required=True, help="the repository root")
    args = parser.parse_args()
    pamdp = str(Path(args.bin).resolve())
    self_test(pamdp)
    files, errors = check(Path(args.root).resolve(), pamdp)
    for e in errors:
        print(f"docs_check: {e}", file=sys.stderr)
    print(f"docs_check: {len(files)} pages, {len(errors)} problems")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
