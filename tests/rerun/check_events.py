"""Reads a sinew .rrd back with rerun-sdk 0.36.3 and checks that an entity holds a text log
entry containing a phrase at a level (usage: check_events.py FILE.rrd ENTITY PHRASE LEVEL)."""

import sys

import rerun.experimental as rrx


def column(batch, name):
    return batch.column(batch.schema.get_field_index(name)).to_pylist()


def main(rrd: str, entity: str, phrase: str, level: str) -> None:
    found = []
    for chunk in rrx.RrdReader(rrd).stream().to_chunks():
        if str(chunk.entity_path) != entity:
            continue
        batch = chunk.to_record_batch()
        names = batch.schema.names
        texts = column(batch, "TextLog:text") if "TextLog:text" in names else []
        levels = column(batch, "TextLog:level") if "TextLog:level" in names else [None] * len(texts)
        for text, lvl in zip(texts, levels):
            text = text[0] if isinstance(text, list) else text
            lvl = lvl[0] if isinstance(lvl, list) else lvl
            found.append((text, lvl))
    assert any(phrase in t and lvl == level for t, lvl in found), f"no {level} entry with {phrase!r} at {entity}: {found}"
    print(f"checked {entity}: {found}")


if __name__ == "__main__":
    main(*sys.argv[1:5])
