#!/usr/bin/env python3
"""Mutation check of the acceptance and SIL tests (docs/mutation.md).

Each mutant in tests/mutation/mutants.json is a small, deliberate bug put
into the firmware: a text replaced where a marker comment in the source
anchors it (`/* mut: ID */` in C, `# mut: ID` in Python, on the mutated
line or the line before it; the text must occur exactly once in the
marker's line and the REGION_LINES lines after it), so that code moved by a
refactor carries its mutant with it and the JSON names no file; or, for an
entry with "file" and no "anchor", an exact text found once in that file.
The tests listed with it must notice, i.e. at least one of them must FAIL
on the mutated build. A mutant no listed test kills is a hole in the tests.

The check works on a copy of the source tree (the caller's files are
never written): it copies the working tree (tracked and untracked files
that git does not ignore) to WORKDIR/src, configures one host-release
build there once (WORKDIR/src/build/host-release), builds the targets the
listed tests need, and requires the unmutated tree to pass every listed
test first. Then, per mutant: apply the edit(s), rebuild only the targets
its tests need, run exactly those tests (ctest -R '^name$', pytest node
ids with FLUXDRIVE_SIL set to the copy's runner), restore the file(s).

host-release, not host-debug: no mutant needs a sanitizer to be seen (each
breaks a behaviour an acceptance or SIL test measures), and the optimised
build runs the SIL tests 2-3x faster (test_preempt: 55 s vs 120 s on a
loaded machine). Without link-time optimisation (FD_SIL_LTO=OFF): every
mutant relinks the runner, and an LTO link costs seconds. A listed test that fails on the unmutated tree is run
once more: passing then, it is reported FLAKY and the check goes on.

    python3 scripts/mutation_check.py                      # all mutants
    python3 scripts/mutation_check.py --only delta_max_65deg v_margin_0_9
    python3 scripts/mutation_check.py --list               # the table, nothing run
    python3 scripts/mutation_check.py --markdown docs/mutation.md   # run, then rewrite its table
    python3 scripts/mutation_check.py --check-markdown docs/mutation.md --list  # docs in sync?
    python3 scripts/mutation_check.py --mutants tests/mutation/survivors.json  # the open holes

Exit status: 0 when every mutant was killed; 1 when a mutant survived, is
stale (its find text is missing or not unique: the message names it) or
does not build; 2 when the unmutated tree fails a listed test or the
setup fails. Python standard library only.
"""

from __future__ import annotations

import argparse
import fcntl
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_MUTANTS = ROOT / "tests" / "mutation" / "mutants.json"
BUILD_REL = Path("build") / "host-release"
SIL_TARGET = "fluxdrive-sil"
SIL_REL = BUILD_REL / "sil" / "fluxdrive-sil"
# excluded from a copy made without git
COPY_IGNORE = {".git", "build", ".venv", "out", "__pycache__", ".pytest_cache"}
# docs sections, one per mutant list (NAME: the list's file stem)
MD_BEGIN = "<!-- mutation-table:begin {} (scripts/mutation_check.py --markdown) -->"
MD_END = "<!-- mutation-table:end {} -->"
TEST_TIMEOUT = 900  # s, one mutant's pytest run (ctest: each test's own TIMEOUT)


# --------------------------------------------------------------- mutants
@dataclass
class Edit:
    file: str | None  # an anchored edit's: the file its marker is in (resolve_anchors)
    find: str
    replace: str
    anchor: str | None = None  # the marker's name: `mut: NAME`


# a marker comment: `mut: NAME` (C /* ... */ or Python #)
MARK_RE = re.compile(r"(?:/\*|#)\s*mut: ([A-Za-z0-9_.#-]+)")
REGION_LINES = 12  # the find text lies within the marker's line and this many after it
MARK_SUFFIXES = (".c", ".h", ".py", ".cmake", ".ld", ".sh")


def markers(root: Path, files: list[str] | None = None) -> dict[str, list[str]]:
    """Marker name -> the files it appears in (files, relative to root;
    default: the source files of root's git work tree)."""
    out: dict[str, list[str]] = {}
    for rel in files if files is not None else source_files(root):
        if not rel.endswith(MARK_SUFFIXES):
            continue
        try:
            text = (root / rel).read_text()
        except (OSError, UnicodeDecodeError):
            continue
        if "mut: " not in text:
            continue
        for m in MARK_RE.finditer(text):
            out.setdefault(m.group(1), []).append(rel)
    return out


def resolve_anchors(root: Path, mutants: list[Mutant],
                    files: list[str] | None = None) -> dict[str, str]:
    """Sets each anchored edit's file from its marker in root (among files,
    default root's source files); returns the mutants whose marker is
    missing or not unique, with the reason."""
    index = markers(root, files) if any(e.anchor for m in mutants for e in m.edits) else {}
    bad: dict[str, str] = {}
    for m in mutants:
        for e in m.edits:
            if e.anchor is None:
                continue
            files = index.get(e.anchor, [])
            if len(files) == 1:
                e.file = files[0]
            else:
                bad[m.id] = (f"marker 'mut: {e.anchor}' "
                             f"{'not found' if not files else 'found in ' + ', '.join(files)} "
                             "(must occur exactly once in the tree)")
    return bad


def locate(text: str, e: Edit) -> int | str:
    """Offset of e's find text in text, or why it cannot be applied."""
    first = e.find.strip().splitlines()[0] if e.find.strip() else e.find
    if e.anchor is None:
        n = text.count(e.find)
        if n == 1:
            return text.index(e.find)
        return (f"find text {'not found' if n == 0 else f'found {n} times'} in {e.file} "
                f"(must occur exactly once): {first!r}")
    hits = [m for m in MARK_RE.finditer(text) if m.group(1) == e.anchor]
    if len(hits) != 1:
        return f"marker 'mut: {e.anchor}' found {len(hits)} times in {e.file}"
    start = text.rfind("\n", 0, hits[0].start()) + 1
    end = start
    for _ in range(REGION_LINES + 1):
        nxt = text.find("\n", end)
        if nxt < 0:
            end = len(text)
            break
        end = nxt + 1
    n = text.count(e.find, start, end)
    if n == 1:
        return text.index(e.find, start, end)
    return (f"find text {'not found' if n == 0 else f'found {n} times'} within {REGION_LINES} "
            f"lines of marker 'mut: {e.anchor}' in {e.file} (must occur exactly once): {first!r}")


@dataclass
class Mutant:
    id: str
    breaks: str
    tests: list[str]
    edits: list[Edit]
    targets: list[str] = field(default_factory=list)
    note: str = ""  # survives_because (known survivors, tests/mutation/survivors.json)
    source: str = "mutants"  # stem of the list it came from: its docs section

    @property
    def files(self) -> list[str]:
        return sorted({e.file for e in self.edits if e.file})


def _text(v) -> str:
    """A find/replace text: a string, or a list of lines joined by newlines."""
    if isinstance(v, list):
        return "\n".join(v)
    if isinstance(v, str):
        return v
    raise ValueError(f"find/replace must be a string or a list of lines, not {type(v).__name__}")


def load_mutants(paths: list[Path]) -> list[Mutant]:
    out: list[Mutant] = []
    for path in paths:
        data = json.loads(path.read_text())
        for m in data["mutants"]:
            where = f"{path}: mutant {m.get('id', '?')}"
            try:
                if "edits" in m:
                    edits = [Edit(e.get("file", m.get("file")), _text(e["find"]), _text(e["replace"]),
                                  e.get("anchor"))
                             for e in m["edits"]]
                else:
                    edits = [Edit(m.get("file"), _text(m["find"]), _text(m["replace"]),
                                  m.get("anchor"))]
                mut = Mutant(m["id"], m["breaks"], list(m["tests"]), edits, list(m.get("targets", [])),
                             m.get("survives_because", ""), path.stem)
            except (KeyError, ValueError) as e:
                raise SystemExit(f"mutation_check: {where}: bad entry ({e})")
            if not mut.tests:
                raise SystemExit(f"mutation_check: {where}: no tests listed")
            for t in mut.tests:
                if not (t.startswith("ctest:") or t.startswith("pytest:")):
                    raise SystemExit(f"mutation_check: {where}: test {t!r} is neither ctest:NAME "
                                     "nor pytest:NODEID")
            if any(e.file is None and e.anchor is None for e in edits):
                raise SystemExit(f"mutation_check: {where}: an edit names neither an anchor nor a file")
            if any(x.id == mut.id for x in out):
                raise SystemExit(f"mutation_check: {where}: duplicate id")
            out.append(mut)
    return out


def targets_of(m: Mutant) -> list[str]:
    """Build targets the mutant's tests need: ctest area/test_x -> area_test_x
    (tests/CMakeLists.txt), pytest -> the SIL runner; plus any listed."""
    t = list(m.targets)
    for test in m.tests:
        kind, name = test.split(":", 1)
        t.append(name.replace("/", "_") if kind == "ctest" else SIL_TARGET)
    return sorted(set(t))


def stale_reason(src: Path, e: Edit) -> str | None:
    if e.file is None:
        return f"marker 'mut: {e.anchor}' not resolved"
    p = src / e.file
    if not p.is_file():
        return f"file {e.file} does not exist"
    where = locate(p.read_text(), e)
    return where if isinstance(where, str) else None


# ------------------------------------------------------------ the copy
def source_files(root: Path) -> list[str]:
    try:
        res = subprocess.run(["git", "-C", str(root), "ls-files", "-z", "--cached", "--others",
                              "--exclude-standard"], capture_output=True, check=True)
        return [f for f in res.stdout.decode().split("\0") if f and (root / f).is_file()]
    except (OSError, subprocess.CalledProcessError):
        files = []
        for dirpath, dirnames, filenames in os.walk(root):
            dirnames[:] = [d for d in dirnames if d not in COPY_IGNORE]
            for f in filenames:
                files.append(str(Path(dirpath, f).relative_to(root)))
        return files


def sync_tree(root: Path, dst: Path) -> int:
    """dst := the source files of root; unchanged files keep their mtime (the
    build stays incremental); files gone from root are removed. Returns the
    number of files written."""
    files = source_files(root)
    written = 0
    for rel in files:
        s, d = root / rel, dst / rel
        data = s.read_bytes()
        if d.is_file() and d.read_bytes() == data:
            continue
        d.parent.mkdir(parents=True, exist_ok=True)
        d.write_bytes(data)
        shutil.copymode(s, d)
        written += 1
    keep = set(files)
    for dirpath, dirnames, filenames in os.walk(dst):
        rel_dir = Path(dirpath).relative_to(dst)
        if rel_dir == Path("."):
            dirnames[:] = [x for x in dirnames if x not in ("build",)]
        dirnames[:] = [x for x in dirnames if x not in ("__pycache__", ".pytest_cache")]
        for f in filenames:
            rel = str(rel_dir / f) if rel_dir != Path(".") else f
            if rel not in keep:
                (dst / rel).unlink()
    return written


# ------------------------------------------------------------- running
def sh(cmd: list[str], cwd: Path, env: dict | None = None, timeout: float | None = None,
       log: Path | None = None) -> tuple[int, str]:
    try:
        res = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
        rc, out = res.returncode, res.stdout + res.stderr
    except subprocess.TimeoutExpired as e:
        rc = -9
        out = (e.stdout or b"").decode(errors="replace") if isinstance(e.stdout, bytes) else (e.stdout or "")
        out += f"\n[timeout after {timeout} s]"
    if log is not None:
        with log.open("a") as fh:
            fh.write(f"$ {' '.join(cmd)}\n{out}\n[exit {rc}]\n")
    return rc, out


class Runner:
    def __init__(self, src: Path, python: str, jobs: int, log: Path):
        self.src, self.python, self.jobs, self.log = src, python, jobs, log
        self.build = src / BUILD_REL

    def configure(self) -> None:
        rc, out = sh(["cmake", "--preset", "host-release", f"-DFD_PYTHON={self.python}",
                      "-DFD_SIL_LTO=OFF"],
                     self.src, log=self.log)
        if rc != 0:
            raise RuntimeError(f"configure failed:\n{out[-3000:]}")

    def build_targets(self, targets: list[str]) -> tuple[bool, str]:
        rc, out = sh(["cmake", "--build", str(self.build), "-j", str(self.jobs), "--target", *targets],
                     self.src, log=self.log)
        return rc == 0, out

    def run_tests(self, tests: list[str], tag: str) -> tuple[list[str], list[str]]:
        """Runs the tests; returns (failed, passed) names as listed."""
        ctests = [t.split(":", 1)[1] for t in tests if t.startswith("ctest:")]
        pytests = [t.split(":", 1)[1] for t in tests if t.startswith("pytest:")]
        failed: list[str] = []
        passed: list[str] = []
        for name in ctests:
            # one at a time, exact name: -R is a regular expression
            rc, out = sh(["ctest", "--test-dir", str(self.build), "-R", f"^{re.escape(name)}$",
                          "--output-on-failure", "--no-tests=error"], self.src, log=self.log)
            if "No tests were found" in out:
                raise RuntimeError(f"ctest knows no test {name!r} (in {self.build})")
            (passed if rc == 0 else failed).append(f"ctest:{name}")
        if pytests:
            junit = self.build / "mutation-junit" / f"{tag}.xml"
            junit.parent.mkdir(parents=True, exist_ok=True)
            if junit.exists():
                junit.unlink()
            env = dict(os.environ)
            env["FLUXDRIVE_SIL"] = str(self.src / SIL_REL)
            # the map tool the runner calls for .npz / .csv maps (the copy has no .venv)
            env["FLUXDRIVE_PYTHON"] = self.python
            env["PYTHONPATH"] = os.pathsep.join([str(self.src / "tools" / "src"),
                                                 env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
            env.pop("FLUXDRIVE_RUBINO_SCENARIOS", None)
            env["MPLBACKEND"] = "Agg"
            # its own temporary directory (not the shared /tmp/pytest-of-USER)
            basetemp = self.build / "mutation-pytest" / tag
            basetemp.parent.mkdir(parents=True, exist_ok=True)
            rc, out = sh([self.python, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                          f"--basetemp={basetemp}", f"--junitxml={junit}", *pytests], self.src, env=env,
                         timeout=TEST_TIMEOUT, log=self.log)
            status = _junit_status(junit) if junit.exists() else {}
            for node in pytests:
                st = status.get(_node_key(node))
                if st == "passed":
                    passed.append(f"pytest:{node}")
                elif st is None and rc == 0:
                    raise RuntimeError(f"pytest ran no test {node!r}")
                elif st == "skipped":
                    raise RuntimeError(f"pytest skipped {node!r} (is the SIL runner built?)")
                else:
                    # failed, error, or no result (crash, timeout): not passed
                    failed.append(f"pytest:{node}")
        return failed, passed


def _node_key(node: str) -> str:
    """pytest node id -> 'module_stem::name' as found in the junit xml."""
    path, _, name = node.partition("::")
    return f"{Path(path).stem}::{name}"


def _junit_status(path: Path) -> dict[str, str]:
    out: dict[str, str] = {}
    for tc in ET.parse(path).getroot().iter("testcase"):
        cls = tc.get("classname", "").split(".")[-1]
        key = f"{cls}::{tc.get('name')}"
        if tc.find("failure") is not None or tc.find("error") is not None:
            out[key] = "failed"
        elif tc.find("skipped") is not None:
            out[key] = "skipped"
        else:
            out[key] = "passed"
    return out


# -------------------------------------------------------------- output
@dataclass
class Result:
    mutant: Mutant
    status: str  # killed | SURVIVED | STALE | NO-BUILD
    failed: list[str]
    seconds: float
    detail: str = ""


def _short(test: str) -> str:
    kind, name = test.split(":", 1)
    if kind == "pytest":
        path, _, fn = name.partition("::")
        return f"{Path(path).stem}::{fn}"
    return name


def text_table(results: list[Result]) -> str:
    rows = [("mutant", "result", "s", "failed test(s)", "what it breaks")]
    for r in results:
        rows.append((r.mutant.id, r.status, f"{r.seconds:.1f}",
                     ", ".join(_short(t) for t in r.failed) or "-", r.mutant.breaks))
    w = [max(len(row[i]) for row in rows) for i in range(4)]
    lines = []
    for k, row in enumerate(rows):
        cells = [c.rjust(w[i]) if i == 2 else c.ljust(w[i]) for i, c in enumerate(row[:4])]
        lines.append("  ".join(cells + [row[4]]))
        if k == 0:
            lines.append("  ".join("-" * x for x in w + [len(row[4])]))
    return "\n".join(lines)


def _md(s: str) -> str:
    return s.replace("|", "\\|")


STATIC_HEAD = ["id", "file", "what it breaks", "tests that must fail (one is enough)"]


def static_cells(m: Mutant) -> list[str]:
    cells = [f"`{m.id}`", ", ".join(f"`{f}`" for f in m.files), _md(m.breaks),
             "<br>".join(f"`{_short(t)}`" for t in m.tests)]
    return cells + ([_md(m.note)] if m.note else [])


def markdown_table(mutants: list[Mutant], results: dict[str, Result] | None) -> str:
    head = STATIC_HEAD + (["why it survives"] if any(m.note for m in mutants) else [])
    head += ["failed on the mutant", "s"] if results else []
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for m in mutants:
        cells = static_cells(m)
        if results:
            r = results.get(m.id)
            if r is None:
                cells += ["not run", ""]
            elif r.status == "killed":
                cells += ["<br>".join(f"`{_short(t)}`" for t in r.failed), f"{r.seconds:.0f}"]
            else:
                cells += [r.status, f"{r.seconds:.0f}"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _split_md(path: Path, name: str) -> tuple[str, str, str]:
    text = path.read_text()
    begin, end = MD_BEGIN.format(name), MD_END.format(name)
    if begin not in text or end not in text:
        raise SystemExit(f"mutation_check: {path} lacks the markers of the {name!r} table\n"
                         f"  {begin}\n  {end}")
    a, rest = text.split(begin, 1)
    body, b = rest.split(end, 1)
    return a + begin, body, end + b


def by_source(mutants: list[Mutant]) -> dict[str, list[Mutant]]:
    out: dict[str, list[Mutant]] = {}
    for m in mutants:
        out.setdefault(m.source, []).append(m)
    return out


def write_markdown(path: Path, mutants: list[Mutant], results: dict[str, Result] | None,
                   summary: str) -> None:
    for name, ms in by_source(mutants).items():
        a, _, b = _split_md(path, name)
        got = [results[m.id] for m in ms if results and m.id in results]
        killed = sum(r.status == "killed" for r in got)
        body = "\n" + markdown_table(ms, results) + "\n"
        if summary and got:
            body += (f"\n{summary}: {killed} of {len(got)} killed in "
                     f"{sum(r.seconds for r in got):.0f} s (the mutants alone: edit, rebuild, tests).\n")
        path.write_text(a + body + b)


def check_markdown(path: Path, mutants: list[Mutant]) -> list[str]:
    """Differences between the tables in path and the mutant lists (the static
    columns: id, file, what it breaks, tests, why it survives)."""
    problems = []
    for name, ms in by_source(mutants).items():
        _, body, _ = _split_md(path, name)
        doc = {}
        for ln in body.splitlines():
            if ln.startswith("| `"):
                cells = [c.strip() for c in re.split(r"(?<!\\)\|", ln.strip())[1:-1]]
                doc[cells[0]] = cells
        for m in ms:
            want = static_cells(m)
            got = doc.pop(want[0], None)
            if got is None:
                problems.append(f"{m.id}: missing from the {name!r} table")
            elif [c for k, c in enumerate(got[:len(want)]) if k != 1] != [c for k, c in enumerate(want) if k != 1]:
                # (the file column, index 1, follows the marker: not compared)
                problems.append(f"{m.id}: row of the {name!r} table differs from {name}.json")
        problems += [f"{k.strip('`')}: in the {name!r} table but not in {name}.json" for k in doc]
    return problems


# ---------------------------------------------------------------- main
def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mutants", type=Path, action="append",
                    help=f"mutant list (JSON); repeatable (default {DEFAULT_MUTANTS.relative_to(ROOT)})")
    ap.add_argument("--only", nargs="+", metavar="ID", help="run only these mutants")
    ap.add_argument("--source", type=Path, default=ROOT, help="tree to copy (default: this one)")
    ap.add_argument("--workdir", type=Path,
                    help="keep the copy and its build here (reused: incremental); default a "
                         "temporary directory, removed afterwards")
    ap.add_argument("--python", default=None,
                    help="Python with pytest and the tools' dependencies (default: .venv/bin/python "
                         "of the source tree, else this interpreter)")
    ap.add_argument("-j", "--jobs", type=int, default=2, help="build jobs (default 2)")
    ap.add_argument("--list", action="store_true",
                    help="print the mutant table, run nothing (after --check-markdown, if given)")
    ap.add_argument("--markdown", type=Path, metavar="MD",
                    help="after the run, rewrite the marked table section of MD with the results")
    ap.add_argument("--check-markdown", type=Path, metavar="MD",
                    help="first check that the table of MD lists exactly these mutants "
                         "(fail if not: regenerate with --markdown)")
    args = ap.parse_args(argv)

    src_root = args.source.resolve()
    mutants = load_mutants(args.mutants or [DEFAULT_MUTANTS])
    resolve_anchors(src_root, mutants)  # the file column of --list and the docs
    if args.only:
        unknown = set(args.only) - {m.id for m in mutants}
        if unknown:
            print(f"mutation_check: unknown mutant(s): {', '.join(sorted(unknown))}", file=sys.stderr)
            return 2
        mutants = [m for m in mutants if m.id in args.only]

    if args.check_markdown:
        problems = check_markdown(args.check_markdown, mutants)
        if problems:
            print(f"mutation_check: {args.check_markdown} is out of sync with the mutant list "
                  f"(run scripts/mutation_check.py --markdown {args.check_markdown}):", file=sys.stderr)
            for p in problems:
                print("  " + p, file=sys.stderr)
            return 1
    if args.list:
        print(markdown_table(mutants, None))
        return 0

    python = args.python
    if python is None:
        venv = src_root / ".venv" / "bin" / "python"
        python = str(venv) if venv.exists() else sys.executable

    t_start = time.monotonic()
    tmp = None
    if args.workdir:
        work = args.workdir.resolve()
        work.mkdir(parents=True, exist_ok=True)
    else:
        tmp = tempfile.mkdtemp(prefix="fd-mutation-")
        work = Path(tmp)
    lock = open(work / ".lock", "w")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        print(f"mutation_check: another check is using {work}", file=sys.stderr)
        return 2
    try:
        return _run(args, src_root, work, python, mutants, t_start)
    finally:
        lock.close()
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)


def _run(args, src_root: Path, work: Path, python: str, mutants: list[Mutant], t_start: float) -> int:
    src = work / "src"
    log = work / "mutation.log"
    log.write_text("")
    n = sync_tree(src_root, src)
    print(f"mutation_check: copy of {src_root} in {src} ({n} files written); log {log}", flush=True)

    # stale mutants: reported, not run
    results: dict[str, Result] = {}
    # the copy is no git work tree of its own (it may lie inside the
    # caller's, under build/): its files are the caller's source files
    unresolved = resolve_anchors(src, mutants, source_files(src_root))
    for m in mutants:
        why = ([unresolved[m.id]] if m.id in unresolved else
               [r for r in (stale_reason(src, e) for e in m.edits) if r])
        if why:
            results[m.id] = Result(m, "STALE", [], 0.0, "; ".join(why))
            print(f"STALE {m.id}: {'; '.join(why)}", flush=True)
    live = [m for m in mutants if m.id not in results]

    runner = Runner(src, python, args.jobs, log)
    t0 = time.monotonic()
    try:
        runner.configure()
        all_targets = sorted({t for m in live for t in targets_of(m)})
        ok, out = runner.build_targets(all_targets)
        if not ok:
            print(f"mutation_check: the unmutated tree does not build:\n{out[-3000:]}", file=sys.stderr)
            return 2
        all_tests = list(dict.fromkeys(t for m in live for t in m.tests))
        failed, _ = runner.run_tests(all_tests, "baseline")
    except RuntimeError as e:
        print(f"mutation_check: {e}", file=sys.stderr)
        return 2
    print(f"baseline: {len(all_tests)} tests on the unmutated tree in {time.monotonic() - t0:.1f} s "
          f"(configure, build {len(all_targets)} targets, run)", flush=True)
    if failed:
        # once more: a test that fails on the unmutated tree only now and
        # then (a random preemption run) is reported, not silently retried
        print(f"mutation_check: WARNING: the unmutated tree failed {', '.join(failed)}; "
              "running it once more", flush=True)
        try:
            again, _ = runner.run_tests(failed, "baseline-again")
        except RuntimeError as e:
            print(f"mutation_check: {e}", file=sys.stderr)
            return 2
        if again:
            print("mutation_check: the unmutated tree fails " + ", ".join(again) +
                  f": the check would be meaningless (log: {log})", file=sys.stderr)
            return 2
        print(f"mutation_check: WARNING: {', '.join(failed)} FLAKY on the unmutated tree "
              f"(failed once, then passed; first output in {log})", flush=True)

    for m in live:
        t0 = time.monotonic()
        originals = {f: (src / f).read_text() for f in m.files}
        try:
            for f in m.files:
                text = originals[f]
                for e in m.edits:
                    if e.file == f:
                        i = locate(text, e)
                        assert isinstance(i, int), i  # checked before (stale_reason)
                        text = text[:i] + e.replace + text[i + len(e.find):]
                (src / f).write_text(text)
            ok, out = runner.build_targets(targets_of(m))
            if not ok:
                err = [ln for ln in out.splitlines() if "error" in ln][:3]
                res = Result(m, "NO-BUILD", [], 0.0, "; ".join(err))
            else:
                failed, _ = runner.run_tests(m.tests, m.id)
                res = Result(m, "killed" if failed else "SURVIVED", failed, 0.0)
        except RuntimeError as e:
            res = Result(m, "ERROR", [], 0.0, str(e))
        finally:
            for f, text in originals.items():
                (src / f).write_text(text)
        res.seconds = time.monotonic() - t0
        results[m.id] = res
        shown = ", ".join(_short(t) for t in res.failed) or res.detail or "no listed test failed"
        print(f"{res.status:8s} {m.id} ({res.seconds:.1f} s): {shown}", flush=True)

    # the copy is back to the unmutated tree: leave its build consistent
    runner.build_targets(sorted({t for m in live for t in targets_of(m)}))

    ordered = [results[m.id] for m in mutants]
    total = time.monotonic() - t_start
    print("\n" + text_table(ordered))
    bad = [r for r in ordered if r.status != "killed"]
    print(f"\n{len(ordered) - len(bad)} of {len(ordered)} mutants killed in {total:.0f} s")
    for r in bad:
        what = {"SURVIVED": f"survived: none of {', '.join(_short(t) for t in r.mutant.tests)} failed",
                "STALE": f"stale: {r.detail}",
                "NO-BUILD": f"does not build: {r.detail}",
                "ERROR": f"error: {r.detail}"}[r.status]
        print(f"  {r.mutant.id}: {what}", file=sys.stderr)
    if args.markdown:
        write_markdown(args.markdown, mutants, results,
                       f"Last run ({time.strftime('%Y-%m-%d')}, host-release copy, -j{args.jobs})")
        print(f"table written to {args.markdown}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
