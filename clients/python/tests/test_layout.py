"""The ctypes mirrors in hnav/msg.py against the Rust layout table, field by field.

    HNAV_LAYOUT_JSON=layout.json python -m unittest discover -s tests

`layout.json` is what `hnav layout --json` prints (tests/tests/python_client.rs makes it);
without HNAV_LAYOUT_JSON the test runs `hnav` from $PATH.
"""

import ctypes
import json
import os
import subprocess
import sys
import typing
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

from hnav import msg  # noqa: E402
from hnav.run import TOPICS  # noqa: E402

import iceoryx2 as iox2  # noqa: E402


def rust_table():
    """The Rust side's table."""
    path = os.environ.get("HNAV_LAYOUT_JSON")
    if path:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    out = subprocess.run(["hnav", "layout", "--json"], check=True, capture_output=True)
    return json.loads(out.stdout)


class LayoutTest(unittest.TestCase):
    """Every payload's type name, size, alignment and field offsets and sizes."""

    @classmethod
    def setUpClass(cls):
        cls.table = rust_table()

    def test_max_agents(self):
        self.assertEqual(msg.MAX_AGENTS, self.table["max_agents"])

    def test_every_rust_type_has_a_mirror(self):
        rust = {t["name"] for t in self.table["types"]}
        mirrors = {t.__name__ for t in msg.PAYLOADS}
        self.assertEqual(rust, mirrors)

    def test_every_mirror_matches_field_by_field(self):
        mirrors = {t.__name__: t for t in msg.PAYLOADS}
        for t in self.table["types"]:
            m = mirrors[t["name"]]
            with self.subTest(type=t["name"]):
                self.assertEqual(m.type_name(), t["type_name"], "type name")
                self.assertEqual(ctypes.sizeof(m), t["size"], "size")
                self.assertEqual(ctypes.alignment(m), t["align"], "alignment")
                names = [f[0] for f in m._fields_]
                self.assertEqual(names, [f["name"] for f in t["fields"]], "field names")
                for f in t["fields"]:
                    field = getattr(m, f["name"])
                    self.assertEqual(
                        field.offset, f["offset"], f"{t['name']}.{f['name']} offset"
                    )
                    self.assertEqual(field.size, f["size"], f"{t['name']}.{f['name']} size")

    def test_every_topic_has_the_rust_types(self):
        rust = {t["topic"]: t for t in self.table["topics"]}
        self.assertEqual(set(rust), set(TOPICS))
        for topic, (payload, header) in TOPICS.items():
            with self.subTest(topic=topic):
                r = rust[topic]
                slice_ = typing.get_origin(payload) is iox2.Slice
                self.assertEqual(slice_, r["slice"], "slice")
                element = typing.get_args(payload)[0] if slice_ else payload
                self.assertEqual(iox2.get_type_name(element), r["payload"], "payload")
                header_name = "()" if header is None else header.type_name()
                self.assertEqual(header_name, r["user_header"], "user header")


if __name__ == "__main__":
    unittest.main()


class ViewTest(unittest.TestCase):
    """A View's bitsets read back as cells: seen, blocked and moving."""

    def test_moving_cells_are_the_seen_cells_marked_moving(self):
        v = msg.View()
        v.x0, v.y0, v.size = 3, 4, 5
        v.seen[0] = 0b00011  # (3, 4) and (4, 4)
        v.blocked[0] = 0b00010  # (4, 4): a mover's disc covers it
        v.moving[0] = 0b00110  # (4, 4), and (5, 4), which is not seen
        self.assertEqual(list(v.cells()), [(3, 4, False), (4, 4, True)])
        self.assertEqual(list(v.moving_cells()), [(4, 4)])
