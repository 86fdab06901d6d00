"""Reads a sinew .rrd back with rerun-sdk 0.36.3 and checks it against the values the Rust test
computed from the simulation (usage: check_rrd.py FILE.rrd EXPECTED.json)."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import rerun.experimental as rrx


def column(batch, name):
    """The values of one component column, as Python lists (no time columns touched)."""
    return batch.column(batch.schema.get_field_index(name)).to_pylist()


def main(rrd: str, expected_path: str) -> None:
    expected = json.loads(Path(expected_path).read_text())
    component = expected["component"]
    surfaces = {}  # step -> flat list of floats
    inverted = {}
    entities = set()
    for chunk in rrx.RrdReader(rrd).stream().to_chunks():
        path = str(chunk.entity_path)
        entities.add(path)
        batch = chunk.to_record_batch()
        names = batch.schema.names
        if path == expected["surface"] and component in names and "step" in names:
            for step, value in zip(column(batch, "step"), column(batch, component)):
                if value is not None:
                    surfaces[step] = np.asarray(value, dtype=np.float64).ravel()
        if path == expected["inverted"] and "Scalars:scalars" in names and "step" in names:
            for step, value in zip(column(batch, "step"), column(batch, "Scalars:scalars")):
                inverted[step] = value

    for key in ("surface", "nodes", "inverted"):
        assert expected[key] in entities, f"missing entity {expected[key]}; have {sorted(entities)}"
    assert any(e.startswith(expected["colliders"]) for e in entities), f"no collider entity in {sorted(entities)}"
    assert "/world/deformables/jelly/surface" in entities

    frames = expected["frames"]
    assert len(inverted) == len(frames), f"{len(inverted)} inverted_elements values for {len(frames)} frames"
    for frame in frames:
        step = frame["step"]
        assert step in surfaces, f"no surface logged at step {step}; have {sorted(surfaces)}"
        got = surfaces[step]
        want = np.asarray(frame["surface"], dtype=np.float64)
        assert got.shape == want.shape, f"step {step}: {got.shape} values, expected {want.shape}"
        err = float(np.max(np.abs(got - want)))
        assert err <= 1e-6, f"step {step}: surface differs from the nodes by {err}"
        assert step in inverted, f"no inverted_elements at step {step}"

    rerun_cli = Path(sys.executable).parent / "rerun"
    verify = subprocess.run([str(rerun_cli), "rrd", "verify", rrd], capture_output=True, text=True)
    assert verify.returncode == 0, f"rerun rrd verify failed: {verify.stdout}\n{verify.stderr}"
    print(f"checked {len(frames)} frames, {len(entities)} entities in {rrd}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
