#!/usr/bin/env bash
# The prepared GPU benchmark: both backends at 1920x1080, 1 spp, voxel and block LOD, 1 and 4
# bounces, on every .svdag file given (or in the folder given), through the C++ tool
# vtksvdag-render (no VTK needed, Rendering/README.md "On a GPU machine"). Prints one table:
# per file, LOD and bounces, the median milliseconds of an accumulating and of a restarting frame
# for each backend, of a restarting frame with the denoiser on (the others run with it off), of
# one traced at half resolution per axis and upsampled guided by labels and depth, denoised (what
# the VTK mapper's interactive frames do: --trace-reduction 2), the denoiser's cost (the denoised
# restarting frame's extra time, in percent of the restarting frame: issue 22's target is at most
# 15% at 512x512, so run it with --width 512 --height 512 as well) and the device bytes
# (encoding + what the backend finds blocks with). Then the start-up of each
# backend on the first file: seconds of a whole one-frame run with every cache empty (the
# driver's disk cache off: __GL_SHADER_DISK_CACHE=0, MESA_SHADER_CACHE_DISABLE=true), the same
# with --preview (first frame from the preview pipeline), with smooth shading and with a clipping
# plane (the feature variants a scene compiles in only when it uses them), and with only our
# pipeline cache (PipelineCacheFile.h) warm; each with its frame's pipeline compile seconds.
#
# Here (to prepare the files from the shared volumes):
#   for f in ../shared/data/*.nrrd; do .venv/bin/vtksvdag compress "$f" -o "DIR/$(basename "$f" .nrrd).svdag"; done
# On the GPU machine (folder BIN holds vtksvdag-render and the libraries it links):
#   bash bench/gpu.sh --bin BIN [--frames 20] [--width 1920 --height 1080] SVDAG_DIR_OR_FILES...
#
# Environment passed to the tool: SVDAG_VK_DEVICE (a device name substring) and the Vulkan
# loader's VK_DRIVER_FILES. Exits non-zero if any run fails (its message is printed).
set -uo pipefail

bin=""
frames=20
width=1920
height=1080
inputs=()
while [ $# -gt 0 ]; do
  case "$1" in
    --bin) bin="$2"; shift 2 ;;
    --frames) frames="$2"; shift 2 ;;
    --width) width="$2"; shift 2 ;;
    --height) height="$2"; shift 2 ;;
    -h|--help) sed -n '2,/^set -uo/{/^#/p}' "$0"; exit 0 ;;
    *) inputs+=("$1"); shift ;;
  esac
done
if [ ${#inputs[@]} -eq 0 ]; then
  echo "usage: bash bench/gpu.sh [--bin DIR] [--frames N] [--width W --height H] SVDAG_DIR_OR_FILES..." >&2
  exit 1
fi
tool="vtksvdag-render"
if [ -n "$bin" ]; then
  tool="$bin/vtksvdag-render"
  export LD_LIBRARY_PATH="$bin${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
fi
files=()
for input in "${inputs[@]}"; do
  if [ -d "$input" ]; then
    for f in "$input"/*.svdag; do [ -e "$f" ] && files+=("$f"); done
  elif [ -f "$input" ]; then
    files+=("$input")
  else
    echo "bench/gpu.sh: $input is neither a .svdag file nor a folder" >&2
    exit 1
  fi
done
if [ ${#files[@]} -eq 0 ]; then
  echo "bench/gpu.sh: no .svdag files in ${inputs[*]}" >&2
  exit 1
fi
if ! command -v "$tool" >/dev/null; then
  echo "bench/gpu.sh: $tool not found (build it, or pass --bin DIR)" >&2
  exit 1
fi

out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
status=0
# One JSON line per run (the tool's own output), tagged with the file.
results="$out/results.jsonl"
for f in "${files[@]}"; do
  for lod in voxel block; do
    for bounces in 1 4; do
      for backend in rt compute; do
        for variant in "--no-denoise" "--restart --no-denoise" "--restart --denoise" \
          "--restart --denoise --trace-reduction 2"; do
          line=$("$tool" "$f" "$out/frame.png" --width "$width" --height "$height" --spp 1 \
            --frames "$frames" --lod "$lod" --bounces "$bounces" --backend "$backend" $variant \
            2>"$out/err")
          if [ $? -ne 0 ]; then
            echo "FAILED: $(basename "$f") $lod $bounces $backend $variant: $(cat "$out/err")" >&2
            status=1
            continue
          fi
          echo "{\"file\": \"$(basename "$f" .svdag)\", \"run\": $line}" >>"$results"
        done
      done
    done
  done
done

# Start-up: a whole one-frame run per backend, every cache empty (with the full pipeline, then
# with --preview: the first frame from the small preview pipeline while the full one compiles,
# then the smooth-shading and the clipping variants), then with our cache warm. The JSON's
# pipeline_compile_seconds: the frame's pipeline's compile.
startup="$out/startup.txt"
for backend in rt compute; do
  cache="$out/cache-$backend"
  for state in cold cold-preview cold-smooth cold-clipped ours-warm; do
    flags=()
    run_cache="$cache"
    case "$state" in
      cold-preview) flags=(--preview) ;;
      cold-smooth) flags=(--shading smooth) ;;
      cold-clipped) flags=(--clip 0,0,0,1,0,0) ;; # where it cuts does not change the compile
    esac
    if [ ${#flags[@]} -gt 0 ]; then
      run_cache="$out/cache-$backend-$state"
    fi
    begin=$(date +%s.%N)
    if json=$(XDG_CACHE_HOME="$run_cache" __GL_SHADER_DISK_CACHE=0 MESA_SHADER_CACHE_DISABLE=true \
      "$tool" "${files[0]}" "$out/frame.png" --width "$width" --height "$height" --spp 1 \
      --frames 1 --backend "$backend" "${flags[@]}" 2>"$out/err"); then
      end=$(date +%s.%N)
      echo "$backend $state $(python3 -c "
import json, sys
r = json.loads(sys.argv[1])
print(f'{$end - $begin:.3f} s, compile {r[\"pipeline_compile_seconds\"]:.3f} s, previewed {r[\"previewed\"]}')
" "$json")" >>"$startup"
    else
      echo "FAILED: start-up $backend $state: $(cat "$out/err")" >&2
      status=1
    fi
  done
done

python3 - "$results" "$width" "$height" "$frames" "$startup" <<'EOF'
import json, sys
path, width, height, frames, startup = sys.argv[1:]
rows = {}
device = ""
try:
    lines = open(path).read().splitlines()
except FileNotFoundError:
    lines = []
for line in lines:
    r = json.loads(line)
    run = r["run"]
    device = run["device"]
    key = (r["file"], run["lod"], run["bounces"])
    kind = ("restart+denoise" if run.get("denoise") else "restart") if run["restart"] else "accumulate"
    if run.get("trace_reduction", 1) > 1:
        kind += f"+r{run['trace_reduction']}"
    rows.setdefault(key, {})[(run["backend"], kind)] = run
print(f"{device}, {width}x{height}, 1 spp, median of {int(frames) - 1} frames after a warm-up (ms)")
print(f"{'volume':<26} {'LOD':>6} {'b':>2} | {'rt acc':>8} {'rt rst':>8} {'rt dn':>8} {'rt dn/2':>8} | "
      f"{'cmp acc':>8} {'cmp rst':>8} {'cmp dn':>8} {'cmp dn/2':>8} | {'rt/cmp':>6} | "
      f"{'rt dn%':>6} {'cmp dn%':>7} | {'rt MB':>6} {'cmp MB':>6}")
for (name, lod, bounces), runs in sorted(rows.items()):
    ms = lambda b, k: runs[(b, k)]["ms_median"] if (b, k) in runs else float("nan")
    mb = lambda b: ((runs[(b, "accumulate")]["bytes_device"]["encoding"] +
                     runs[(b, "accumulate")]["bytes_device"]["acceleration"]) / 1e6
                    if (b, "accumulate") in runs else float("nan"))
    ratio = ms("rt", "accumulate") / ms("compute", "accumulate")
    # The denoiser's cost in percent of the restarting frame it filters.
    cost = lambda b: 100.0 * (ms(b, "restart+denoise") / ms(b, "restart") - 1.0)
    print(f"{name:<26} {lod:>6} {bounces:>2} | {ms('rt', 'accumulate'):8.2f} {ms('rt', 'restart'):8.2f} "
          f"{ms('rt', 'restart+denoise'):8.2f} {ms('rt', 'restart+denoise+r2'):8.2f} | "
          f"{ms('compute', 'accumulate'):8.2f} {ms('compute', 'restart'):8.2f} "
          f"{ms('compute', 'restart+denoise'):8.2f} {ms('compute', 'restart+denoise+r2'):8.2f} | "
          f"{ratio:6.2f} | {cost('rt'):6.0f} {cost('compute'):7.0f} | {mb('rt'):6.2f} {mb('compute'):6.2f}")
try:
    print("\nstart-up, seconds of a one-frame run (every cache empty; empty with --preview, with"
          " smooth shading, with a clipping plane; only our pipeline cache warm)")
    for line in open(startup).read().splitlines():
        print("  " + line)
except FileNotFoundError:
    pass
EOF
exit $status
