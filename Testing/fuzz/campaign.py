#!/usr/bin/env python3
"""Run fuzz_readers.py over many targets for a time budget and summarise the campaign.

Each target runs in its own atheris process for its share of the budget; when it stops on a
finding (a crash, a hang, an unexpected exception, a silently wrong volume) the input is copied to
``<out>/findings/<target>-<kind>-<sha1>`` with the log beside it, and the target starts again
for the rest of its share (so one campaign can find several). The summary (inputs tried per
target, accepted, rejected, exact checks, soft findings, findings) is printed as a table and
written to ``<out>/summary.json``.

    campaign.py --seconds 60 --out /tmp/fz                   # every target, 60 s in all
    campaign.py --seconds 3600 --per-target --out bench/out/fuzz nrrd_gzip svdag
"""
import argparse
import hashlib
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import time

HERE = pathlib.Path(__file__).resolve().parent
HARNESS = HERE / "fuzz_readers.py"
sys.path.insert(0, str(HERE))

# Tokens of the text headers and interesting numbers, for libFuzzer's dictionary mutations.
DICTIONARY = [
    "NRRD0004", "NRRD0005", "type:", "dimension:", "sizes:", "encoding:", "endian:", "raw", "gzip",
    "gz", "bzip2", "ascii", "hex", "big", "little", "data file:", "LIST", "space directions:",
    "space origin:", "kinds:", "byte skip:", "line skip:", "uchar", "int8", "uint16", "int64",
    "unsigned long long", "float", "double", "block", "none", "space dimension:", "measurement frame:",
    "ObjectType = Image", "NDims = ", "DimSize = ", "ElementType = ", "MET_UCHAR", "MET_SHORT",
    "MET_LONG_LONG", "MET_FLOAT", "ElementDataFile = ", "LOCAL", "CompressedData = ",
    "CompressedDataSize = ", "BinaryDataByteOrderMSB = ", "ElementNumberOfChannels = ",
    "HeaderSize = ", "True", "False", "TransformMatrix = ", "ElementSpacing = ", "Offset = ",
    "0", "1", "-1", "16", "65535", "65536", "2147483647", "2147483648", "4294967295", "4294967296",
    "18446744073709551615", "9223372036854775808", "1e308", "nan", "inf", "-0",
    "\\x00\\x00\\x00\\x80", "\\xff\\xff\\xff\\xff", "\\xff\\xff\\xff\\x7f", "\\x00\\x00\\x00\\x00",
    "\\x01\\x00\\x00\\x00", "\\x10\\x00\\x00\\x00", "\\xff\\xff\\xff\\xff\\xff\\xff\\xff\\xff",
    "\\x00\\x00\\x00\\x00\\x00\\x00\\xf0\\x7f",
    "<VTKFile", "ImageData", "WholeExtent=", "Piece", "PointData", "DataArray", "format=",
    "appended", "binary", "UInt16", "Int64", "NumberOfComponents=", "offset=", "AppendedData",
    "compressor=", "vtkZLibDataCompressor", "header_type=", "UInt64", "byte_order=", "BigEndian",
]


def write_dictionary(path):
    path.write_text("".join(f'"{token}"\n' for token in DICTIONARY))


def _finding_kind(log):
    if "Uncaught Python exception" in log:
        match = re.search(r"^(\w*(?:Error|Exception|Volume)\w*):", log, re.M)
        return "exception-" + (match.group(1) if match else "unknown")
    if "ALARM: working on the last Unit" in log or "libFuzzer: timeout" in log:
        return "hang"
    if "out-of-memory" in log:
        return "oom"
    if "deadly signal" in log or "AddressSanitizer" in log or "SEGV" in log:
        return "signal"
    return "crash"


def run_target(target, seconds, out, python=sys.executable, timeout=10, rss_mb=4096, env=None):
    """Fuzz one target for ``seconds``; returns its summary dict."""
    from fuzz_readers import write_seed_corpus

    seeds = out / "seeds" / target
    corpus = out / "corpus" / target
    artifacts = out / "artifacts" / target
    findings = out / "findings"
    logs = out / "logs"
    for d in (corpus, artifacts, findings, logs):
        d.mkdir(parents=True, exist_ok=True)
    seed_paths = write_seed_corpus(target, seeds)
    max_len = 2 * max(p.stat().st_size for p in seed_paths) + 256
    dictionary = out / "fuzz.dict"
    if not dictionary.exists():
        write_dictionary(dictionary)
    summary = {"target": target, "inputs": 0, "accepted": 0, "rejected": 0,
               "accepted_exact_checked": 0, "soft": 0, "findings": [], "runs": 0}
    deadline = time.monotonic() + seconds
    while True:
        left = int(deadline - time.monotonic())
        if left < 1:
            break
        stats_path = out / "stats" / f"{target}.json"
        if stats_path.exists():
            stats_path.unlink()
        command = [python, str(HARNESS), "--target", target, "--workdir", str(out),
                   f"-max_total_time={left}", f"-timeout={timeout}", f"-rss_limit_mb={rss_mb}",
                   f"-max_len={max_len}", f"-dict={dictionary}", "-print_final_stats=1",
                   f"-artifact_prefix={artifacts}/", str(corpus), str(seeds)]
        log_path = logs / f"{target}-{summary['runs']}.log"
        with open(log_path, "w") as log:
            proc = subprocess.run(command, stdout=log, stderr=subprocess.STDOUT, env=env,
                                  timeout=left + 4 * timeout + 120)
        summary["runs"] += 1
        text = log_path.read_text(errors="replace")
        executed = re.findall(r"stat::number_of_executed_units:\s*(\d+)", text)
        stats = json.loads(stats_path.read_text()) if stats_path.exists() else {}
        summary["inputs"] += int(executed[-1]) if executed else stats.get("inputs", 0)
        for key in ("accepted", "rejected", "accepted_exact_checked", "soft"):
            summary[key] += stats.get(key, 0)
        for key, n in stats.get("soft_kinds", {}).items():
            summary.setdefault("soft_kinds", {})[key] = summary.get("soft_kinds", {}).get(key, 0) + n
        if proc.returncode == 0:
            break
        kind = _finding_kind(text)
        saved = None
        for artifact in sorted(artifacts.iterdir()):
            data = artifact.read_bytes()
            name = f"{target}-{kind}-{hashlib.sha1(data).hexdigest()[:12]}"
            shutil.copy(artifact, findings / name)
            shutil.copy(log_path, findings / f"{name}.log")
            artifact.unlink()
            saved = str(findings / name)
            summary["findings"].append(saved)
        if saved is None:
            summary["findings"].append(f"{target}-{kind} (no input saved, see {log_path})")
            break
    return summary


def main():
    from fuzz_readers import TARGETS

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("targets", nargs="*", help="default: all")
    parser.add_argument("--seconds", type=float, default=60, help="budget for all targets")
    parser.add_argument("--per-target", action="store_true", help="--seconds is for each target")
    parser.add_argument("--out", default="/tmp/vtksvdag-fuzz")
    parser.add_argument("--timeout", type=int, default=10, help="seconds per input")
    args = parser.parse_args()
    targets = args.targets or list(TARGETS)
    out = pathlib.Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    start = time.monotonic()
    results = []
    for i, target in enumerate(targets):
        if args.per_target:
            share = args.seconds
        else:  # what is left, shared by the targets still to run
            share = (args.seconds - (time.monotonic() - start)) / (len(targets) - i)
        results.append(run_target(target, max(share, 2), out, timeout=args.timeout))
        r = results[-1]
        print(f"{target:14s} {r['inputs']:9d} inputs {r['accepted']:8d} accepted "
              f"{r['rejected']:8d} rejected {r['accepted_exact_checked']:8d} exact "
              f"{r['soft']:5d} soft {len(r['findings']):3d} findings", flush=True)
    total = sum(r["inputs"] for r in results)
    found = [f for r in results for f in r["findings"]]
    print(f"{total} inputs in {time.monotonic() - start:.0f} s, {len(found)} findings")
    for f in found:
        print("  finding:", f)
    (out / "summary.json").write_text(json.dumps(results, indent=1))
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
