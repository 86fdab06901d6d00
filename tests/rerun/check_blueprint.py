"""Reads the blueprint sinew sent with a recording back with rerun-sdk 0.36.3 and checks the
layout a user sees (usage: check_blueprint.py FILE.rrd EXPECTED.json).

EXPECTED.json: {"class": "3D" | "2D", "bodies": [names], "box": [[lo...], [hi...]] (the
deformables' box at the first frame), "ground": size of the largest collider, m}.

Checks:
- the viewport has a root container and asks for no automatic views (so rerun's cap of 8
  automatic views per kind hides nothing);
- a world view of the class asked for, reachable from the root, whose contents include every
  deformable's surface (and so the wireframe and colliders under /world);
- every /stats/ entity of the recording is in some time-series view reachable from the root;
  with several bodies, each plot holds one metric, a series per body;
- the legend is in a text view;
- 3D: the eye looks at a point inside the deformables' framing and sits within a few body sizes
  of it (the ground, much larger, does not set the zoom); 2D: the visual bounds contain the
  deformables' box and are a few body sizes across, not the ground's size.
"""

import json
import sys
from pathlib import Path

import numpy as np
import rerun.experimental as rrx


def rows(reader, store):
    """entity path -> {component: last value} for one store."""
    out = {}
    for chunk in reader.stream(store=store).to_chunks():
        batch = chunk.to_record_batch()
        entry = out.setdefault(str(chunk.entity_path), {})
        for name in batch.schema.names:
            if ":" not in name:
                continue
            for value in batch.column(batch.schema.get_field_index(name)).to_pylist():
                if value is not None:
                    entry[name] = value
    return out


def unwrap(value):
    """A component cell is a list of one value (or the values of a batch)."""
    return value[0] if isinstance(value, list) and len(value) == 1 else value


def included(entity, queries, origin):
    """Rerun's entity path filter: '+ expr' / '- expr' / 'expr' lines, '/**' a subtree."""
    def matches(expr):
        expr = expr.replace("$origin", origin.rstrip("/") or "")
        if not expr.startswith("/"):
            expr = "/" + expr
        if expr.endswith("/**"):
            base = expr[:-3]
            return entity == base or entity.startswith(base + "/") or base == ""
        return entity == expr

    inc, exc = False, False
    for line in queries:
        for rule in line.splitlines():
            rule = rule.strip()
            if not rule:
                continue
            if rule.startswith("-"):
                exc |= matches(rule[1:].strip())
            else:
                inc |= matches(rule.lstrip("+").strip())
    return inc and not exc


def main(rrd, expected_path):
    expected = json.loads(Path(expected_path).read_text())
    reader = rrx.RrdReader(rrd)
    recordings, blueprints = reader.recordings(), reader.blueprints()
    assert recordings, "no recording store"
    assert blueprints, "no blueprint in the file"
    data = rows(reader, recordings[0])
    bp = rows(reader, blueprints[-1])

    viewport = bp.get("/viewport", {})
    assert "ViewportBlueprint:root_container" in viewport, f"no root container: {viewport}"
    assert unwrap(viewport.get("ViewportBlueprint:auto_views")) is False, "automatic views are on"
    root = bytes(unwrap(viewport["ViewportBlueprint:root_container"]))

    def uuid_text(b):
        h = b.hex()
        return f"{h[:8]}-{h[8:12]}-{h[12:16]}-{h[16:20]}-{h[20:]}"

    # Walk the layout from the root: every view a user can reach.
    views, stack = [], [f"/container/{uuid_text(root)}"]
    while stack:
        path = stack.pop()
        entry = bp.get(path)
        assert entry is not None, f"{path} is in the layout but not in the blueprint"
        if path.startswith("/container/"):
            stack.extend("/" + c for c in entry.get("ContainerBlueprint:contents", []))
        else:
            views.append(path)

    def view(path):
        entry = bp[path]
        return (
            unwrap(entry["ViewBlueprint:class_identifier"]),
            unwrap(entry.get("ViewBlueprint:space_origin", "/")),
            bp.get(path + "/ViewContents", {}).get("ViewContents:query", []),
        )

    bodies = expected["bodies"]
    surfaces = [f"/world/deformables/{b}/surface" for b in bodies]
    world_views = [
        v for v in views
        if view(v)[0] == expected["class"] and all(included(s, view(v)[2], view(v)[1]) for s in surfaces)
    ]
    assert world_views, f"no {expected['class']} view holding {surfaces}: {[view(v) for v in views]}"
    for s in surfaces:
        assert s in data, f"{s} is not in the recording"

    plots = [view(v) for v in views if view(v)[0] == "TimeSeries"]
    stats = sorted(e for e in data if e.startswith("/stats/") and any(k.startswith("Scalars:") for k in data[e]))
    assert stats, "no stats series in the recording"
    for entity in stats:
        assert any(included(entity, q, o) for _, o, q in plots), f"{entity} is in no plot"
    metrics = {e.rsplit("/", 1)[1] for e in stats}
    if len(bodies) > 1:
        for _, origin, queries in plots:
            shown = [e for e in stats if included(e, queries, origin)]
            assert len({e.rsplit("/", 1)[1] for e in shown}) == 1, f"a plot of several metrics: {shown}"
            assert len(shown) == len(bodies), f"a plot without a series per body: {shown}"

    assert any(view(v)[0] == "TextDocument" and included("/legend", view(v)[2], view(v)[1]) for v in views), "no legend view"
    assert "TextDocument:text" in data.get("/legend", {}), "no legend text"

    lo, hi = np.array(expected["box"][0]), np.array(expected["box"][1])
    size = float(np.linalg.norm(hi - lo))
    ground = float(expected["ground"])
    world = world_views[0]
    if expected["class"] == "3D":
        eye = bp.get(world + "/EyeControls3D", {})
        target = np.array(unwrap(eye["EyeControls3D:look_target"]), dtype=float)
        position = np.array(unwrap(eye["EyeControls3D:position"]), dtype=float)
        centre = 0.5 * (lo + hi)
        distance = float(np.linalg.norm(position - target))
        assert np.all(target >= lo - size) and np.all(target <= hi + size), f"eye looks at {target}, away from the body {lo}..{hi}"
        assert size <= distance <= 5.0 * size + 0.1 * np.linalg.norm(target - centre), f"eye {distance:.2f} m from its target (body {size:.2f} m)"
        assert distance < ground / 4, f"eye {distance:.2f} m away: framed on the ground ({ground} m)"
        print(f"checked: eye {distance:.2f} m from {target}, tracking {eye.get('EyeControls3D:tracking_entity')}")
    else:
        ranges = unwrap(bp[world + "/VisualBounds2D"]["VisualBounds2D:range"])
        x, y = np.array(ranges["x_range"], dtype=float), np.array(ranges["y_range"], dtype=float)
        bounds = np.array([x, y])
        # The view sees world mirrored in y.
        assert x[0] <= lo[0] and x[1] >= hi[0] and y[0] <= -hi[1] and y[1] >= -lo[1], f"bounds {bounds} miss the body {lo}..{hi}"
        assert x[1] - x[0] < ground / 4, f"bounds {bounds} framed on the ground ({ground} m)"
        print(f"checked: bounds {bounds.tolist()}")
    print(f"checked {len(views)} views, {len(plots)} plots, {len(stats)} series ({len(metrics)} metrics)")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
