"""Reads `Scalars` series of a sinew .rrd back with rerun-sdk 0.36.3 and compares them with the
values the Rust test took from the simulation (usage: check_series.py FILE.rrd EXPECTED.json).

EXPECTED.json: {"series": {"/stats/<name>/<path>": [[step, value], ...], ...}}; each series must
hold exactly those steps, each value within 1e-6 relative (1e-9 absolute) of the expected one.
"""

import json
import sys
from pathlib import Path

import rerun.experimental as rrx


def main(rrd: str, expected_path: str) -> None:
    expected = json.loads(Path(expected_path).read_text())["series"]
    found = {path: {} for path in expected}
    for chunk in rrx.RrdReader(rrd).stream().to_chunks():
        path = str(chunk.entity_path)
        if path not in found:
            continue
        batch = chunk.to_record_batch()
        names = batch.schema.names
        if "Scalars:scalars" not in names or "step" not in names:
            continue
        steps = batch.column(batch.schema.get_field_index("step")).to_pylist()
        values = batch.column(batch.schema.get_field_index("Scalars:scalars")).to_pylist()
        for step, value in zip(steps, values):
            found[path][step] = value[0] if isinstance(value, list) else value
    for path, rows in expected.items():
        got = found[path]
        assert len(got) == len(rows), f"{path}: {len(got)} values for {len(rows)} frames"
        for step, value in rows:
            assert step in got, f"{path}: nothing at step {step}"
            tolerance = max(1e-9, 1e-6 * abs(value))
            assert abs(got[step] - value) <= tolerance, f"{path} at step {step}: {got[step]} != {value}"
    print(f"checked {len(expected)} series in {rrd}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
