"""Runs every stiff and extreme case (Testing/Python/extreme_cases.py, their one definition),
times each and writes docs/stability.md: one row per case (group, what was checked, measured
error, tolerance, seconds, pass/fail), then the fuzzing and sanitizer results that
scripts/fuzz.sh and scripts/sanitize.sh leave in bench/out/fuzz/summary.json and
build-asan/sanitize-summary.txt ("not run" where absent), and the date and machine.

    xvfb-run -a .venv/bin/python bench/stability.py            # the cases pytest runs
    xvfb-run -a .venv/bin/python bench/stability.py --large    # also the DAG > 128 MiB case
    .venv/bin/python bench/stability.py --fuzz-only            # only the fuzzing section
Exit status 1 when a case failed.
"""
import argparse
import datetime
import json
import math
import os
import pathlib
import platform
import re
import sys
import time

REPO = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "Testing" / "Python"))

import extreme_cases  # noqa: E402 (after the path)


def format_error(value):
    if math.isinf(value):
        return "inf"
    if math.isnan(value):
        return "nan"
    if value == 0:
        return "0"
    return f"{value:.3g}"


def machine():
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    device = ""
    try:
        from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGRenderer
        renderer = vtkSegmentationSVDAGRenderer()
        renderer.SetWidth(1)
        renderer.SetHeight(1)
        import numpy as np

        import vtksvdag
        renderer.SetInputData(vtksvdag.from_numpy(np.ones((1, 1, 1), np.uint8)).dataobject)
        renderer.Render()
        device = renderer.GetDeviceName()
    except Exception as error:  # noqa: BLE001 (only a description)
        device = f"unavailable ({error})"
    return (f"{platform.node()}: {cpu}, {os.cpu_count()} logical cores, {platform.system()} "
            f"{platform.release()}, Python {platform.python_version()}, Vulkan device: {device}")


def replay_outcome(path):
    """What reading a regression input does now: its target's replay (a clean refusal or a
    right volume passes), as 'refused: <message>', 'read exactly' or 'FAILS: ...'."""
    import subprocess
    import tempfile

    target = path.name.split("--")[0]
    with tempfile.TemporaryDirectory() as work:
        result = subprocess.run(
            [sys.executable, str(REPO / "Testing" / "fuzz" / "fuzz_readers.py"), "--target", target,
             "--workdir", work, "--replay", str(path)], capture_output=True, text=True, timeout=300)
    if result.returncode != 0:
        return "**FAILS**: " + (result.stderr.strip().splitlines() or ["no output"])[-1]
    stats = json.loads(result.stdout.strip().splitlines()[-1])
    if stats.get("rejected"):
        # The harness reads a copy in its work folder: the message names that path.
        message = re.sub(r"Cannot read \S+: ", "", stats.get("last_rejection", ""))
        return "refused: " + message.replace("|", "/")
    return "read exactly" if stats.get("accepted_exact_checked") else "read, consistent"


def fuzz_section(summary=REPO / "bench" / "out" / "fuzz" / "summary.json",
                 sanitize=REPO / "build-asan" / "sanitize-summary.txt"):
    sys.path.insert(0, str(REPO / "Testing" / "fuzz"))
    from fuzz_readers import GENERATORS, TARGETS

    lines = ["## Fuzzing and sanitizers", ""]
    lines.append("### Fuzzing (`bench/out/fuzz/summary.json`, written by `scripts/fuzz.sh`)")
    lines.append("")
    if summary.is_file():
        try:
            runs = json.loads(summary.read_text())
        except ValueError:
            runs = None
        if isinstance(runs, list):
            lines += ["| target | inputs | accepted | rejected | accepted, checked exactly | findings |",
                      "|---|---|---|---|---|---|"]
            for r in runs:
                lines.append(f"| {r.get('target')} | {r.get('inputs', 0):,} | {r.get('accepted', 0):,} "
                             f"| {r.get('rejected', 0):,} | {r.get('accepted_exact_checked', 0):,} "
                             f"| {len(r.get('findings', []))} |")
            total = sum(r.get("inputs", 0) for r in runs)
            found = sum(len(r.get("findings", [])) for r in runs)
            lines += ["", f"{total:,} inputs, {found} findings."]
            missing = [t for t in TARGETS if t not in {r.get("target") for r in runs}]
            if missing:
                lines += ["", "Targets this campaign did not run (added since): "
                          + ", ".join(f"`{t}`" for t in missing) + "."]
        else:
            lines += ["```", summary.read_text().strip(), "```"]
    else:
        lines.append("not run")
    lines += ["", "Generator targets: their inputs carry one kind of damage, made by a custom "
              "mutator (`Testing/fuzz/README.md`):", ""]
    # Each generator's docstring up to its parenthesis says what it damages.
    lines += [f"- `{t}`: {' '.join(g.__doc__.split('(')[0].split())}."
              for t, g in GENERATORS.items()]
    crashes = sorted(p for p in (REPO / "Testing" / "fuzz" / "crashes").glob("*")
                     if p.is_file() and p.name != "README.md")
    if crashes:
        lines += ["", "Every input the fuzzer ever found, kept in `Testing/fuzz/crashes/` and replayed by "
                  "`Testing/Python/test_fuzz.py` (each must be refused cleanly or read exactly), "
                  "and what reading it does now:", "",
                  "| input | now |", "|---|---|"]
        lines += [f"| `{c.name}` | {replay_outcome(c)} |" for c in crashes]
    lines.append("")
    lines.append("### Sanitizers (`build-asan/sanitize-summary.txt`, written by "
                 "`scripts/sanitize.sh`)")
    lines.append("")
    if sanitize.is_file():
        lines += ["```", sanitize.read_text().strip(), "```"]
    else:
        lines.append("not run")
    lines.append("")
    return lines


def rewrite_fuzz_section(path, section):
    """Replaces the fuzzing and sanitizer section of an existing stability.md by `section`
    (fuzz_section's lines), keeping the cases and their run line as they were measured."""
    text = path.read_text()
    begin = text.index("## Fuzzing and sanitizers")
    end = text.index("## Run", begin)
    path.write_text(text[:begin] + "\n".join(section) + "\n" + text[end:])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--large", action="store_true",
                        help="also run the large cases (a DAG buffer over 128 MiB: ~1024^3 voxels)")
    parser.add_argument("--out", type=pathlib.Path, default=REPO / "docs" / "stability.md")
    parser.add_argument("-k", default="", help="only cases whose name contains this")
    parser.add_argument("--fuzz-only", action="store_true",
                        help="rewrite only the fuzzing and sanitizer section of --out (after a "
                        "campaign, or new regression inputs), without running the cases")
    args = parser.parse_args(argv)
    if args.fuzz_only:
        rewrite_fuzz_section(args.out, fuzz_section())
        print(f"wrote the fuzzing section of {args.out}")
        return 0
    cases = extreme_cases.CASES + (extreme_cases.LARGE_CASES if args.large else [])
    cases = [c for c in cases if args.k in c.case_name]
    rows = []
    started = time.perf_counter()
    for function in cases:
        t0 = time.perf_counter()
        outcome = extreme_cases.run_case(function)
        outcome["seconds"] = time.perf_counter() - t0
        rows.append(outcome)
        print(f"{'pass' if outcome['passed'] else 'FAIL'} {outcome['seconds']:7.2f} s  "
              f"{outcome['group']:8s} {outcome['name']}: error {format_error(outcome['error'])} "
              f"(tolerance {format_error(outcome['tolerance'])})"
              + ("" if outcome["passed"] else f"  {outcome['detail']}"), flush=True)
    total = time.perf_counter() - started
    failed = [r for r in rows if not r["passed"]]
    if not args.large:
        skipped = ", ".join(c.case_name for c in extreme_cases.LARGE_CASES)
    lines = [
        "# Stability: stiff and extreme cases",
        "",
        "Generated by `bench/stability.py` from the cases in `Testing/Python/extreme_cases.py` "
        "(the same cases `Testing/Python/test_extreme.py` asserts). Errors are measured against "
        "the CPU ray caster, a numpy brute force or an analytic answer; 0 is exact, inf a plain "
        "wrong answer (a miss for a hit, another label or dtype).",
        "",
        f"{len(rows) - len(failed)} of {len(rows)} cases passed in {total:.1f} s"
        + ("" if args.large else f" (large cases not run: {skipped}; `--large` runs them)") + ".",
        "",
        "| group | case | what was checked | error | tolerance | seconds | result |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        checked = r["checked"].replace("|", "/")
        lines.append(f"| {r['group']} | {r['name']} | {checked} | {format_error(r['error'])} | "
                     f"{format_error(r['tolerance'])} | {r['seconds']:.2f} | "
                     f"{'pass' if r['passed'] else '**FAIL**'} |")
    lines.append("")
    if failed:
        lines += ["## Failures", ""]
        for r in failed:
            lines.append(f"- **{r['name']}** ({r['group']}): {r['checked']}; error "
                         f"{format_error(r['error'])} > tolerance {format_error(r['tolerance'])}; "
                         f"{r['detail'].replace('|', '/')}")
        lines.append("")
    lines += fuzz_section()
    lines += ["## Run", "",
              f"{datetime.datetime.now().astimezone().strftime('%Y-%m-%d %H:%M %Z')}, "
              f"{machine()}", ""]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(lines))
    print(f"{len(rows) - len(failed)} of {len(rows)} passed in {total:.1f} s; wrote {args.out}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
