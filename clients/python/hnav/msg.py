"""ctypes mirrors of every payload in runtime/src/msg/, byte for byte.

Each class has the field names, order and C types of its Rust `#[repr(C)]` struct and the
iceoryx2 type name the Rust side gives it (`#[type_name("hnav::...")]`), so a service opened
with it matches the one the run created. `hnav layout --json` prints the Rust table; the
layout test (tests/test_layout.py) compares every size, alignment and offset with these.

Enumerations travel as plain integers; the constants below name their values.
"""

import ctypes

# The largest run (msg::MAX_AGENTS). No payload is an array of this length: a commit and the
# ground truth are slices sized to the run, read with `slice_of` below.
MAX_AGENTS = 4096
# "No cell" in a cell field (msg::NO_CELL).
NO_CELL = 0xFFFFFFFF


class _Payload(ctypes.Structure):
    """A payload with an iceoryx2 type name: `hnav::<class name>`."""

    @classmethod
    def type_name(cls) -> str:
        """The system-wide type name the Rust side registers the service with."""
        return f"hnav::{cls.__name__}"


class Candidate(_Payload):
    """One agent's request for a round (`round.rs`)."""

    _fields_ = [
        ("round", ctypes.c_uint64),
        ("agent", ctypes.c_uint32),
        ("current", ctypes.c_uint32),
        ("next", ctypes.c_uint32),
        ("probable", ctypes.c_uint32),
        ("priority", ctypes.c_float),
        ("speed", ctypes.c_float),
        ("flags", ctypes.c_uint32),
        ("reserved", ctypes.c_uint32),
    ]


class CandidateFlags:
    """Bits of `Candidate.flags`."""

    AT_GOAL = 1 << 0
    STANDING = 1 << 1
    LOCAL_EXTREMUM = 1 << 2
    RESTARTED = 1 << 3
    NO_PATH = 1 << 4


class Verdict:
    """Values of `Decision.verdict`."""

    ACCEPT = 1
    BLOCK = 2
    HOLD = 3
    REPLAN = 4
    TASK = 5
    NAMES = {1: "accept", 2: "block", 3: "hold", 4: "replan", 5: "task"}


class ConflictKind:
    """Values of `Decision.kind`."""

    NAMES = {
        0: "none",
        1: "crossing",
        2: "head-on",
        3: "combined",
        4: "stable-cell",
        5: "corner-cut",
        6: "reserved",
        7: "invalid",
    }


class Decision(_Payload):
    """What the coordinator decided for one agent in a round."""

    _fields_ = [
        ("agent", ctypes.c_uint32),
        ("verdict", ctypes.c_uint8),
        ("refused", ctypes.c_uint8),
        ("kind", ctypes.c_uint8),
        ("reserved", ctypes.c_uint8),
        ("cell", ctypes.c_uint32),
        ("waypoint", ctypes.c_uint32),
    ]


class CommitHeader(_Payload):
    """The user header of one decided round (`commit`, a slice of Decision, one per agent of
    the run): read `count` decisions with `slice_of` (the binding's slice length is in
    bytes)."""

    _fields_ = [
        ("round", ctypes.c_uint64),
        ("count", ctypes.c_uint32),
        ("term", ctypes.c_uint32),
    ]


class Progress(_Payload):
    """The coordinator's running tally."""

    _fields_ = [
        ("round", ctypes.c_uint64),
        ("agents", ctypes.c_uint32),
        ("at_goal", ctypes.c_uint32),
        ("conflicts", ctypes.c_uint32),
        ("replans", ctypes.c_uint32),
        ("done", ctypes.c_uint8),
        ("leader", ctypes.c_uint8),
        ("reserved", ctypes.c_uint8 * 6),
    ]


class WheelCommand(_Payload):
    """An agent's wheel speeds for one period (`motion.rs`)."""

    _fields_ = [
        ("period", ctypes.c_uint64),
        ("agent", ctypes.c_uint32),
        ("flags", ctypes.c_uint32),
        ("left_rad_s", ctypes.c_double),
        ("right_rad_s", ctypes.c_double),
    ]


class Pose(_Payload):
    """A planar pose in metres and radians (x right, y down the map's rows)."""

    _fields_ = [
        ("x_m", ctypes.c_double),
        ("y_m", ctypes.c_double),
        ("theta_rad", ctypes.c_double),
    ]


class Odometry(_Payload):
    """One robot's Hall-sensor ticks at the end of a period; `fix` is a localisation fix
    when bit 0 of `flags` is set."""

    _fields_ = [
        ("sim_time_ns", ctypes.c_uint64),
        ("period", ctypes.c_uint64),
        ("agent", ctypes.c_uint32),
        ("flags", ctypes.c_uint32),
        ("ticks_left", ctypes.c_int64),
        ("ticks_right", ctypes.c_int64),
        ("fix", Pose),
    ]


class TruthHeader(_Payload):
    """The user header of the sim's ground truth (`truth`, a slice of Pose, one per robot):
    the time, the collisions so far, and `robots`, the poses to read with `slice_of`."""

    _fields_ = [
        ("sim_time_ns", ctypes.c_uint64),
        ("period", ctypes.c_uint64),
        ("robots", ctypes.c_uint32),
        ("collisions", ctypes.c_uint32),
    ]


class Estimate(_Payload):
    """An agent's dead-reckoned pose, once per control period (`estimate` topic)."""

    _fields_ = [
        ("sim_time_ns", ctypes.c_uint64),
        ("agent", ctypes.c_uint32),
        ("reserved", ctypes.c_uint32),
        ("pose", Pose),
    ]


class Role:
    """Values of a `role` byte."""

    NAMES = {1: "sim", 2: "coordinator", 3: "agent"}


class LifecycleEvent:
    """Values of `Lifecycle.event`."""

    NAMES = {
        1: "up",
        2: "down",
        3: "restarted",
        4: "start",
        5: "stop",
        6: "hold",
        7: "resume",
        8: "phase",
        9: "lost",
        10: "roster",
    }


class Lifecycle(_Payload):
    """The supervisor's protocol (`lifecycle.rs`)."""

    _fields_ = [
        ("time_ns", ctypes.c_uint64),
        ("pid", ctypes.c_uint32),
        ("index", ctypes.c_uint32),
        ("role", ctypes.c_uint8),
        ("event", ctypes.c_uint8),
        ("reason", ctypes.c_uint8),
        ("reserved", ctypes.c_uint8),
        ("restarts", ctypes.c_uint32),
    ]


class Heartbeat(_Payload):
    """A process's proof of life (`health.rs`)."""

    _fields_ = [
        ("t_ns", ctypes.c_uint64),
        ("seq", ctypes.c_uint64),
        ("pid", ctypes.c_uint32),
        ("index", ctypes.c_uint32),
        ("role", ctypes.c_uint8),
        ("reserved", ctypes.c_uint8 * 7),
    ]


class ActivationKind:
    """Values of `MapHeader.activation`."""

    NAMES = {1: "linear", 2: "tanh", 3: "route"}


class MapHeader(_Payload):
    """The user header of a neural-map snapshot (a slice of f32, one value per cell, row-major)."""

    _fields_ = [
        ("round", ctypes.c_uint64),
        ("agent", ctypes.c_uint32),
        ("width", ctypes.c_uint32),
        ("height", ctypes.c_uint32),
        ("iterations", ctypes.c_uint32),
        ("target", ctypes.c_uint32),
        ("activation", ctypes.c_uint8),
        ("reserved", ctypes.c_uint8 * 3),
    ]


class View(_Payload):
    """What robot `agent`'s range sensor sees: a `size` x `size` window of cells from
    (`x0`, `y0`); bit `c` of row `r` is cell (`x0 + c`, `y0 + r`), in `seen` if it is in range
    and in line of sight, in `blocked` if it is then a wall, a closed cell or a mover's, in
    `moving` if a mover holds it: stands in it or walks the leg into or out of it (then it says
    nothing about the map)."""

    _fields_ = [
        ("sim_time_ns", ctypes.c_uint64),
        ("period", ctypes.c_uint64),
        ("agent", ctypes.c_uint32),
        ("x0", ctypes.c_uint32),
        ("y0", ctypes.c_uint32),
        ("size", ctypes.c_uint32),
        ("seen", ctypes.c_uint32 * 32),
        ("blocked", ctypes.c_uint32 * 32),
        ("moving", ctypes.c_uint32 * 32),
    ]

    def cells(self):
        """Every cell seen, as (x, y, blocked), row by row."""
        size = min(self.size, 32)
        for r in range(size):
            for c in range(size):
                if self.seen[r] >> c & 1:
                    yield (self.x0 + c, self.y0 + r, bool(self.blocked[r] >> c & 1))

    def moving_cells(self):
        """Every cell seen that a mover holds, as (x, y), row by row."""
        for x, y, _ in self.cells():
            if self.moving[y - self.y0] >> (x - self.x0) & 1:
                yield (x, y)


# The most cells one Sighting carries (msg::SIGHTING_CELLS).
SIGHTING_CELLS = 32


class Sighting(_Payload):
    """Cells robot `agent` saw change from the swarm's picture, sent before its candidate for
    `round`: `cells[k]` (k < count) closed if bit k of `closed` is set, else it opened."""

    _fields_ = [
        ("round", ctypes.c_uint64),
        ("agent", ctypes.c_uint32),
        ("count", ctypes.c_uint32),
        ("closed", ctypes.c_uint32),
        ("reserved", ctypes.c_uint32),
        ("cells", ctypes.c_uint32 * SIGHTING_CELLS),
    ]

    def changes(self):
        """Every cell, as (cell index, closed)."""
        for k in range(min(self.count, SIGHTING_CELLS)):
            yield (self.cells[k], bool(self.closed >> k & 1))


class WorldHeader(_Payload):
    """The user header of the coordinator's map (`world`, a slice of u32): `to` words of
    addressee bits (bit i % 32 of word i // 32 names agent i, a restarted agent it answers),
    then the cells that differ from the scenario's map after `round`, the `closed` ones first,
    then the `opened` ones. Read to + closed + opened words: the binding's slice length is in
    bytes."""

    _fields_ = [
        ("round", ctypes.c_uint64),
        ("closed", ctypes.c_uint32),
        ("opened", ctypes.c_uint32),
        ("to", ctypes.c_uint32),
        ("reserved", ctypes.c_uint32),
    ]

    def split(self, words):
        """A sample's words (a list) as (addressees, closed cells, opened cells)."""
        to = words[: self.to]
        cells = words[self.to : self.to + self.closed + self.opened]
        agents = [i for i in range(32 * len(to)) if to[i // 32] >> (i % 32) & 1]
        return agents, cells[: self.closed], cells[self.closed :]


def slice_of(element, count, sample):
    """The first `count` elements of type `element` of a slice sample's payload, copied out
    (the sample's memory goes back to its publisher when the sample is dropped). `count` comes
    from the header: the binding reports a slice's length in bytes, not elements."""
    return list((element * count).from_address(sample.payload().as_ptr()))


# Every payload mirror, for the layout test.
class MoversHeader(_Payload):
    """The user header of the sim's `movers` topic (a slice of MoverPlace): where the moving
    obstacles on the floor are at the end of control period `period` (read len // 32 places:
    the binding's slice length is in bytes)."""

    _fields_ = [
        ("sim_time_ns", ctypes.c_uint64),
        ("period", ctypes.c_uint64),
    ]


class MoverPlace(_Payload):
    """One mover on the floor: its index (the order the movers appeared in) and its pose."""

    _fields_ = [
        ("mover", ctypes.c_uint32),
        ("reserved", ctypes.c_uint32),
        ("pose", Pose),
    ]


class WheelsHeader(_Payload):
    """The user header of `wheels/<first>` (a slice of WheelCommand): the latest command of
    each robot of the agent process whose first robot is `first`; `count` elements follow."""

    _fields_ = [
        ("first", ctypes.c_uint32),
        ("count", ctypes.c_uint32),
    ]


class OdometryHeader(_Payload):
    """The user header of `odom/<first>` (a slice of Odometry): one reading per robot of the
    agent process whose first robot is `first`; `count` elements follow."""

    _fields_ = [
        ("first", ctypes.c_uint32),
        ("count", ctypes.c_uint32),
    ]


class ViewsHeader(_Payload):
    """The user header of `view/<first>` (a slice of View): one view per robot of the agent
    process whose first robot is `first`; `count` elements follow."""

    _fields_ = [
        ("first", ctypes.c_uint32),
        ("count", ctypes.c_uint32),
    ]


PAYLOADS = [
    Candidate,
    Decision,
    CommitHeader,
    Progress,
    WheelCommand,
    Odometry,
    Pose,
    TruthHeader,
    Estimate,
    Lifecycle,
    Heartbeat,
    MapHeader,
    View,
    Sighting,
    WorldHeader,
    MoversHeader,
    MoverPlace,
    WheelsHeader,
    OdometryHeader,
    ViewsHeader,
]
