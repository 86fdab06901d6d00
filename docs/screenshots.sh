#!/usr/bin/env bash
# Screenshots of the Rerun viewer on the main demo's recordings (README, "Viewing runs in Rerun"):
# docs/screenshots/fall-impact-3d.png and fall-impact-2d.png, the edge-repulsion runs of
# `cargo run --release --features rerun --example fall_and_bounce` at the impact frame (the frame
# of the smallest volume ratio), as the viewer draws them with the layout sinew sends; and
# docs/screenshots/asset.png, the trefoil knot of `--example asset` drawn by its render mesh
# as its bone lets it go (README, "From your own mesh").
#
# The viewer plays a file from its start in simulated time (the layout's time panel) and stops at
# its end, so the demo runs twice: once whole, to find the impact frame in its recording, then
# again up to that frame (the same run, cut there); the screenshot shows that last frame.
#
# Needs: Xvfb and a Vulkan driver (Debian: `apt-get install xvfb mesa-vulkan-drivers`; the
# viewer then renders on the CPU with llvmpipe) and Python 3 with pip (the viewer comes from
# rerun-sdk==0.36.3 in target/rerun-venv, made here if missing).
set -euo pipefail
cd "$(dirname "$0")/.."

venv=target/rerun-venv
if [ ! -x "$venv/bin/rerun" ]; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check "rerun-sdk==0.36.3"
fi
"$venv/bin/rerun" analytics disable >/dev/null 2>&1 || true

out=target/screenshots
rm -rf "$out"
mkdir -p "$out" docs/screenshots
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"

# shoot RRD NAME: the viewer's screenshot of recording RRD, halved, to docs/screenshots/NAME.png.
shoot() {
    local rrd="$1" name="$2" png="$out/$2.png"
    # The viewer saves the screenshot, then may exit non-zero on its way out; the file decides.
    # The screen is larger than the window so that Xvfb's pointer (at the screen's centre) is
    # not over the window, where it would open a hover tooltip.
    # RUST_LOG=error: no notification toasts (Docker, software rasterizer) over the plots.
    RUST_LOG=error timeout 300 xvfb-run -a -s "-screen 0 6400x4000x24" "$venv/bin/rerun" \
        "$rrd" --renderer vulkan \
        --window-size 1400x860 --screenshot-to "$png" >"$out/viewer-$name.log" 2>&1 || true
    if [ ! -s "$png" ]; then
        echo "no screenshot; the viewer said:" >&2
        tail -20 "$out/viewer-$name.log" >&2
        exit 1
    fi
    # Half size for the repository (the viewer renders at twice the window's points).
    "$venv/bin/python" - "$png" "docs/screenshots/$name.png" <<'PY'
import sys
from PIL import Image
image = Image.open(sys.argv[1])
image = image.resize((image.width // 2, image.height // 2), Image.LANCZOS)
image.save(sys.argv[2], optimize=True)
print(f"wrote {sys.argv[2]} ({image.width}x{image.height})")
PY
}

cargo build --release --features rerun --example fall_and_bounce
demo=target/release/examples/fall_and_bounce
"$demo" --rrd "$out/whole" >/dev/null

for dim in 3d 2d; do
    # The step (1 ms each) of the smallest volume ratio, from the whole run's recording.
    seconds=$("$venv/bin/python" - "$out/whole/$dim-edge-repulsion.rrd" <<'PY'
import sys
import rerun.experimental as rrx
best = None
for chunk in rrx.RrdReader(sys.argv[1]).stream().to_chunks():
    if str(chunk.entity_path) != "/stats/jelly/min_volume_ratio":
        continue
    batch = chunk.to_record_batch()
    if not {"step", "Scalars:scalars"} <= set(batch.schema.names):
        continue  # the static series name
    col = lambda n: batch.column(batch.schema.get_field_index(n)).to_pylist()
    for step, value in zip(col("step"), col("Scalars:scalars")):
        v = value[0] if isinstance(value, list) else value
        if best is None or v < best[1]:
            best = (step, v)
print(f"{best[0] * 1e-3:.3f}")
print(f"impact at step {best[0]}: smallest volume ratio {best[1]:.3f}", file=sys.stderr)
PY
)
    "$demo" --rrd "$out/impact-$dim" --seconds "$seconds" >/dev/null
    shoot "$out/impact-$dim/$dim-edge-repulsion.rrd" "fall-impact-$dim"
done

# The asset, cut at 1.6 s: just let go by its bone, its render mesh over its cells.
cargo build --release --features rerun --example asset
target/release/examples/asset --rrd "$out/asset" --seconds 1.6 >/dev/null
shoot "$out/asset/torus-knot.rrd" asset
