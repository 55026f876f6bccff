#!/usr/bin/env python3
"""Two builds of the scenario parser compared byte for byte.

    scripts/scenario_equiv.py record RUNNER OUT.json [--mutants]
    scripts/scenario_equiv.py compare A.json B.json

`record` runs RUNNER (a fluxdrive-sil) with --dump-scenario on every
scenario file of the repository (sil/scenarios, tests/) and, with
--mutants, on variants of each (every key removed, given a string, a huge,
a negative, a fractional number, null; an unknown key added to every
object), and writes per input the exit code, the error message and the
SHA-256 of the parsed scenario's bytes (pointers zeroed). `compare` prints
the inputs where two records differ; exit 1 if any. Used to prove the
table-driven parser (sil/runner/scenario_keys.h) parses every file to the
same values and refuses every variant with the same message.
"""
import copy
import hashlib
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
VALUES = ["x", 1e30, -1e30, -1, 0, 2.5, None, True, [], {}]


def scenario_files():
    out = []
    for d in ("sil/scenarios", "tests"):
        for p in sorted((ROOT / d).rglob("*.json")):
            try:
                if '"duration"' in p.read_text(errors="replace"):
                    out.append(p)
            except OSError:
                pass
    return out


def paths(node, prefix=()):
    """Every key path of the JSON tree (objects and array elements)."""
    yield prefix, node
    if isinstance(node, dict):
        for k, v in node.items():
            yield from paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from paths(v, prefix + (i,))


def mutants(doc):
    for path, node in list(paths(doc)):
        if isinstance(node, dict):
            m = copy.deepcopy(doc)
            at = m
            for k in path:
                at = at[k]
            at["zz_unknown"] = 1
            yield "/".join(map(str, path)) + "+zz", m
    for path, _ in list(paths(doc)):
        if not path or isinstance(path[-1], int):
            continue
        m = copy.deepcopy(doc)
        at = m
        for k in path[:-1]:
            at = at[k]
        del at[path[-1]]
        yield "/".join(map(str, path)) + "-", m
        for i, v in enumerate(VALUES):
            m = copy.deepcopy(doc)
            at = m
            for k in path[:-1]:
                at = at[k]
            at[path[-1]] = v
            yield "/".join(map(str, path)) + f"={i}", m


def run(runner, path, dump):
    if os.path.exists(dump):
        os.unlink(dump)
    r = subprocess.run([runner, str(path), "--dump-scenario", dump], capture_output=True,
                       text=True, errors="replace", timeout=120)
    digest = ""
    if r.returncode == 0 and os.path.exists(dump):
        digest = hashlib.sha256(Path(dump).read_bytes()).hexdigest()
    return {"rc": r.returncode, "err": r.stderr.strip(), "sha256": digest}


def record(runner, out, with_mutants):
    res = {}
    tmp = Path(tempfile.gettempdir()) / "scenario_equiv"
    tmp.mkdir(exist_ok=True)
    dump = str(tmp / "dump.bin")
    for f in scenario_files():
        rel = str(f.relative_to(ROOT))
        res[rel] = run(runner, f, dump)
        if not with_mutants:
            continue
        try:
            doc = json.loads(f.read_text())
        except ValueError:
            continue
        for name, m in mutants(doc):
            # beside the original: relative map paths resolve the same way
            mp = f.parent / ".equiv_mutant.json"
            mp.write_text(json.dumps(m))
            try:
                res[rel + "#" + name] = run(runner, mp, dump)
            finally:
                mp.unlink()
    Path(out).write_text(json.dumps(res, indent=0, sort_keys=True))
    ok = sum(1 for v in res.values() if v["rc"] == 0)
    print(f"{len(res)} inputs: {ok} parsed, {len(res) - ok} refused")


# Messages the table-driven parser words better (B), mapped back to the
# old wording (A) for the comparison; each counted and reported.
IMPROVED = [
    # an object's keys listed when it is not an object
    (re.compile(r"(must be an object) \([^)]*\)$"), r"\1"),
    # board.timer_counts, board.watchdog_ms: the value, as every integer key
    (re.compile(r"(board\.(timer_counts|watchdog_ms): must be an integer) \(got [^)]*\)$"), r"\1"),
]


def compare(a, b):
    ra, rb = json.loads(Path(a).read_text()), json.loads(Path(b).read_text())
    bad, improved = 0, [0] * len(IMPROVED)
    for k in sorted(set(ra) | set(rb)):
        va, vb = ra.get(k), rb.get(k)
        if va != vb and va is not None and vb is not None and va["rc"] == vb["rc"]:
            err = vb["err"]
            for i, (rx, rep) in enumerate(IMPROVED):
                new = rx.sub(rep, err)
                if new != err and new == va["err"]:
                    improved[i] += 1
                    vb = dict(vb, err=new)
                    break
        if va != vb:
            bad += 1
            print(f"{k}:\n  A {va}\n  B {vb}")
    for (rx, _), n in zip(IMPROVED, improved):
        print(f"reworded ({rx.pattern}): {n}")
    print(f"{len(set(ra) | set(rb))} inputs, {bad} differ")
    return 1 if bad else 0


if __name__ == "__main__":
    if len(sys.argv) >= 4 and sys.argv[1] == "record":
        record(sys.argv[2], sys.argv[3], "--mutants" in sys.argv[4:])
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        sys.exit(compare(sys.argv[2], sys.argv[3]))
    else:
        sys.exit(__doc__)
