"""Joining a live HNAV run: its iceoryx2 config, service names and typed subscriptions.

A run with id RUN keeps everything under its own iceoryx2 file prefix `hnav_RUN_` and names
every service `hnav/RUN/<topic>` (runtime/src/transport/run.rs); a host NAME of a run across
hosts (`hnav run --host NAME`) uses `hnav_RUN.NAME_`, its iceoryx2 domain (`domain=`, else
`$HNAV_DOMAIN`, as on the Rust side); its node and service files
live under one root directory per user: `$HNAV_IPC_ROOT`, else `/tmp/iceoryx2/` for root and
`/tmp/iceoryx2-<uid>/` for everyone else. A client built with another prefix or root sees
nothing of the run.

Every data service is paired with an event service of the same name: publishers notify on it
after each sample, so a client blocks on a listener instead of polling.
"""

import ctypes
import os
import re
import time

import iceoryx2 as iox2

from . import msg

# The environment variable that replaces the per-user iceoryx2 root (transport::IPC_ROOT_ENV).
IPC_ROOT_ENV = "HNAV_IPC_ROOT"
# The environment variable naming the iceoryx2 domain (transport::DOMAIN_ENV).
DOMAIN_ENV = "HNAV_DOMAIN"

# Every topic of a run: payload and user header (None: no header), as runtime/src/topics.rs
# opens them. `<i>` stands for an agent index, `<first>` for the first robot of an agent process
# (every robot's own index with the default of one robot a process).
TOPICS = {
    "wheels/<first>": (iox2.Slice[msg.WheelCommand], msg.WheelsHeader),
    "odom/<first>": (iox2.Slice[msg.Odometry], msg.OdometryHeader),
    "view/<first>": (iox2.Slice[msg.View], msg.ViewsHeader),
    "truth": (iox2.Slice[msg.Pose], msg.TruthHeader),
    "candidates": (msg.Candidate, None),
    "commit": (iox2.Slice[msg.Decision], msg.CommitHeader),
    "map/<i>": (iox2.Slice[ctypes.c_float], msg.MapHeader),
    "progress": (msg.Progress, None),
    "ready": (msg.Lifecycle, None),
    "lifecycle": (msg.Lifecycle, None),
    "heartbeat": (msg.Heartbeat, None),
    "estimate": (msg.Estimate, None),
    "sightings": (msg.Sighting, None),
    "world": (iox2.Slice[ctypes.c_uint32], msg.WorldHeader),
    "movers": (iox2.Slice[msg.MoverPlace], msg.MoversHeader),
}

_RUN_ID = re.compile(r"^[A-Za-z0-9_-]{1,48}$")
_DOMAIN = re.compile(r"^[A-Za-z0-9_-]{1,16}$")


class RunError(Exception):
    """A run id that is not valid, or a service of the run that could not be opened."""


def ipc_root() -> str:
    """The directory where iceoryx2 keeps this user's node and service files."""
    root = os.environ.get(IPC_ROOT_ENV, "")
    if not root:
        root = "/tmp/iceoryx2/" if os.geteuid() == 0 else f"/tmp/iceoryx2-{os.geteuid()}/"
    return root if root.endswith("/") else root + "/"


def run_prefix(run_id: str, domain: "str | None" = None) -> str:
    """The iceoryx2 file prefix of run `run_id`: `hnav_RUN_`, or `hnav_RUN.DOMAIN_` in a
    domain (`domain`, else `$HNAV_DOMAIN`)."""
    if not _RUN_ID.match(run_id):
        raise RunError(
            f"{run_id!r} is not a run id: 1 to 48 ASCII letters, digits, '-' and '_'"
        )
    if domain is None:
        domain = os.environ.get(DOMAIN_ENV, "")
    if not domain:
        return f"hnav_{run_id}_"
    if not _DOMAIN.match(domain):
        raise RunError(
            f"{domain!r} is not a domain (a host's name): 1 to 16 ASCII letters, digits, '-' and '_'"
        )
    return f"hnav_{run_id}.{domain}_"


def run_config(run_id: str, domain: "str | None" = None) -> "iox2.config.Config":
    """The iceoryx2 config of run `run_id` (in `domain`): the defaults with its prefix and
    this user's root."""
    config = iox2.config.default()
    config.global_cfg.prefix = iox2.FileName.new(run_prefix(run_id, domain))
    config.global_cfg.root_path = iox2.Path.new(ipc_root())
    return config


def topic_types(topic: str):
    """The payload and user-header types of `topic` (`commit`, `map/3`, ...)."""
    key = re.sub(r"/\d+$", "/<i>", topic)
    if key not in TOPICS:
        key = re.sub(r"/\d+$", "/<first>", topic)
    if key not in TOPICS:
        raise RunError(f"{topic!r} is not a topic of an HNAV run ({', '.join(TOPICS)})")
    return TOPICS[key]


class Topic:
    """A subscription to one topic: its subscriber and the listener of its event service."""

    def __init__(self, name: str, subscriber, listener):
        self.name = name
        self.subscriber = subscriber
        self.listener = listener

    def drain(self):
        """Yields every unread sample, oldest first. A sample holds a chunk of the run's
        shared memory until it is dropped, and a subscriber may hold only a few: take what
        you need from each before asking for the next."""
        # Events first, then samples: a sample published in between wakes the next wait.
        self.listener.try_wait()
        while True:
            sample = self.subscriber.receive()
            if sample is None:
                return
            yield sample
            del sample

    def wait(self, timeout_s: float):
        """Blocks until the topic's publisher notifies or `timeout_s` passes."""
        self.listener.timed_wait(iox2.Duration.from_secs_f64(timeout_s))


# Where iceoryx2 keeps service files under its root: its default `global.service.directory`,
# which run_config leaves as it is (so does the Rust side).
SERVICE_DIR = "services"


def _belongs_to_run(name: str, prefix: str) -> bool:
    """Whether iceoryx2 file `name` is one of the run with file prefix `prefix`: the prefix,
    then `node` or a hash of 16 or more hex digits (so run `a` does not take run `a_b`'s
    files); transport::run::belongs_to_run on the Rust side."""
    if not name.startswith(prefix):
        return False
    first = re.split(r"[_.]", name[len(prefix):], maxsplit=1)[0]
    return first == "node" or re.fullmatch(r"[0-9A-Fa-f]{16,}", first) is not None


def run_is_live(run_id: str, domain: "str | None" = None) -> bool:
    """Whether run `run_id` (in `domain`) has services right now: a service file of its
    prefix under this user's iceoryx2 root."""
    prefix = run_prefix(run_id, domain)
    try:
        names = os.listdir(os.path.join(ipc_root(), SERVICE_DIR))
    except OSError:
        return False
    return any(_belongs_to_run(n, prefix) for n in names)


class Run:
    """A client's node in a live run.

    The node is created only once the run is seen live (`run_is_live`, waited for up to
    `wait_s`): iceoryx2 makes a management segment in /dev/shm for the first node of a file
    prefix and nothing removes it but the run's supervisor at the run's end, so a node made
    for a mistyped run id would leave `/dev/shm/hnav_<id>_..._global_mgmt` behind for good.
    `close()` (or leaving a `with Run(...)` block) drops the node and its files at once.
    """

    def __init__(
        self,
        run_id: str,
        node_name: str = "python-client",
        wait_s: float = 0.0,
        domain: "str | None" = None,
    ):
        self.run_id = run_id
        self.config = run_config(run_id, domain)
        self.node = None
        deadline = time.monotonic() + wait_s
        while not run_is_live(run_id, domain):
            if time.monotonic() >= deadline:
                raise RunError(
                    f"no live run {run_id!r}: no service of it under {ipc_root()}"
                    f"{' within ' + str(wait_s) + ' s' if wait_s > 0 else ''} "
                    "(`hnav ps` lists the live runs)"
                )
            time.sleep(0.05)
        self.node = (
            iox2.NodeBuilder.new()
            .config(self.config)
            .name(iox2.NodeName.new(node_name))
            .create(iox2.ServiceType.Ipc)
        )

    def close(self) -> None:
        """Drops the node (its files with it); the run goes on."""
        self.node = None

    def __enter__(self) -> "Run":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def service_name(self, topic: str) -> str:
        """The full service name of `topic`: `hnav/<run-id>/<topic>`."""
        return f"hnav/{self.run_id}/{topic}"

    def subscribe(self, topic: str, timeout_s: float = 30.0) -> Topic:
        """Subscribes to `topic`, waiting up to `timeout_s` for the run to create it.

        The service is opened without QoS requirements, so it is taken as the run made it
        (buffers, history, overflow): a client never changes what the run's processes see. A
        late subscriber receives the topic's history (the last sample of state topics) at once.
        """
        payload, header = topic_types(topic)
        name = iox2.ServiceName.new(self.service_name(topic))
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                builder = self.node.service_builder(name).publish_subscribe(payload)
                if header is not None:
                    builder = builder.user_header(header)
                service = builder.open()
                events = self.node.service_builder(name).event().open()
                break
            except (iox2.PublishSubscribeOpenError, iox2.EventOpenError) as e:
                if time.monotonic() >= deadline:
                    raise RunError(
                        f"cannot open {self.service_name(topic)} within {timeout_s} s "
                        f"(is run {self.run_id!r} live? `hnav ps` lists the runs): {e}"
                    ) from e
                time.sleep(0.05)
        return Topic(
            self.service_name(topic),
            service.subscriber_builder().create(),
            events.listener_builder().create(),
        )
