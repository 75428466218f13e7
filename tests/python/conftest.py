"""Shared helpers of the interop tests: start the real node binary on a random ROS domain,
talk to it over DDS with the PyPI `cyclonedds` package (ROS 2 names: topic `rt/...`,
type `pkg::msg::dds_::Type_`, services on the rmw_cyclonedds wire format)."""

from __future__ import annotations

import fcntl
import math
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

sys.path.insert(0, str(Path(__file__).resolve().parent))

import ros_types as rt  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(os.environ.get("DEVELOPABLE_SIM_BIN", ROOT / "target" / "release" / "developable_sim"))
SCENES = ROOT / "config" / "scenes"
TEST_SCENES = Path(__file__).resolve().parent / "scenes"

# Every wait in these tests is bounded; these are generous on a loaded 2-core machine.
READY_TIMEOUT = 20.0
DISCOVERY_TIMEOUT = 10.0


def _cdr1(*policies):
    # ROS 2 speaks XCDR1 (encapsulation 00 01); ask Cyclone for it explicitly
    return Qos(*policies, Policy.DataRepresentation(use_cdrv0_representation=True))


SENSOR_QOS = _cdr1(
    Policy.Reliability.BestEffort,
    Policy.History.KeepLast(5),
    Policy.Durability.Volatile,
)


def reliable_qos(depth: int = 10, transient_local: bool = False) -> Qos:
    return _cdr1(
        Policy.Reliability.Reliable(duration(seconds=1)),
        Policy.History.KeepLast(depth),
        Policy.Durability.TransientLocal if transient_local else Policy.Durability.Volatile,
    )


_used_domains: set[int] = set()
# Suites running at the same time on one machine (a soak next to CI, two worktrees) pick
# their domains at random from the same range; a lock file per domain keeps them apart.
DOMAIN_LOCKS = Path(tempfile.gettempdir()) / "developable_sim_domains"


@pytest.fixture
def domain_id():
    """A random ROS domain per test that no other test uses meanwhile, in this process
    (never twice) or in another (an flock on DOMAIN_LOCKS/<id>.lock, held to the end)."""
    DOMAIN_LOCKS.mkdir(exist_ok=True)
    rng = random.SystemRandom()
    for _ in range(10000):
        d = rng.randint(1, 200)
        if d in _used_domains:
            continue
        lock = open(DOMAIN_LOCKS / f"{d}.lock", "w")
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            lock.close()
            continue
        _used_domains.add(d)
        yield d
        lock.close()  # releases the flock
        return
    raise RuntimeError(f"no free ROS domain in 1..200 ({DOMAIN_LOCKS})")


class NodeProcess:
    """The real node binary, started with `args`, logging to a file."""

    def __init__(self, tmp_path: Path, domain: int, args: list[str], name: str = "node"):
        self.log_path = tmp_path / f"{name}.log"
        self._log = open(self.log_path, "w")
        env = dict(os.environ, ROS_DOMAIN_ID=str(domain))
        self.proc = subprocess.Popen(
            [str(BIN), *args],
            cwd=ROOT,
            env=env,
            stdout=self._log,
            stderr=subprocess.STDOUT,
        )

    def log(self) -> str:
        if not self._log.closed:
            self._log.flush()
        return self.log_path.read_text()

    def wait_ready(self, timeout: float = READY_TIMEOUT) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if "[developable_sim] ready" in self.log():
                return
            if self.proc.poll() is not None:
                raise AssertionError(f"node exited with {self.proc.returncode}:\n{self.log()}")
            time.sleep(0.05)
        raise AssertionError(f"node not ready after {timeout} s:\n{self.log()}")

    def running(self) -> bool:
        return self.proc.poll() is None

    def stop(self, sig: int = signal.SIGINT, timeout: float = 15.0) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            rc = self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            raise AssertionError(f"node did not stop within {timeout} s:\n{self.log()}")
        self._log.close()
        return rc

    def wait_exit(self, timeout: float) -> int:
        try:
            return self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            raise AssertionError(f"node still running after {timeout} s:\n{self.log()}")


@pytest.fixture
def start_node(tmp_path, domain_id):
    # (domain_id: set up before and torn down after this fixture, so the domain's lock
    # outlives the nodes)
    """start_node(domain, *args) -> a ready NodeProcess; stopped at test end."""
    started: list[NodeProcess] = []

    def start(domain: int, *args: str, wait: bool = True, name: str = "node") -> NodeProcess:
        n = NodeProcess(tmp_path, domain, ["node", *args], name=name)
        started.append(n)
        if wait:
            n.wait_ready()
        return n

    yield start
    for n in started:
        if n.running():
            n.stop(signal.SIGKILL)
        # pytest shows a test's captured output only when it fails: then the nodes' own
        # account (held or unseen service replies, dropped publications, TF) is beside it
        tail = n.log().splitlines()[-40:]
        print(f"--- {n.log_path} (last {len(tail)} lines)\n" + "\n".join(tail))


class Ros:
    """A Cyclone DDS participant speaking ROS 2 names."""

    # Entity lifetimes follow one rule, because of a use-after-free in cyclonedds-python
    # 11.0.1 (docs/ros2_interop.md "The Cyclone DDS Python client"): a type's Topic lives
    # as long as the participant (one Topic per name, never one per call), and close()
    # deletes readers, then writers, then the participant, instead of leaving the order
    # to the garbage collector.

    def __init__(self, domain: int):
        self.dp = DomainParticipant(domain)
        self._topics: dict[str, Topic] = {}
        self._readers: list[DataReader] = []
        self._writers: list[DataWriter] = []
        self._clients: dict[str, tuple[DataWriter, DataReader]] = {}
        self._seq = 0
        self.guid = random.getrandbits(63)

    def topic(self, name: str, typ, prefix: str = "rt") -> Topic:
        key = f"{prefix}{name}"
        if key not in self._topics:
            self._topics[key] = Topic(self.dp, key, typ)
        return self._topics[key]

    def reader(self, name: str, typ, qos: Qos | None = None, prefix: str = "rt") -> DataReader:
        r = DataReader(self.dp, self.topic(name, typ, prefix), qos=qos or reliable_qos())
        self._readers.append(r)
        return r

    def writer(self, name: str, typ, qos: Qos | None = None, prefix: str = "rt") -> DataWriter:
        w = DataWriter(self.dp, self.topic(name, typ, prefix), qos=qos or SENSOR_QOS)
        self._writers.append(w)
        return w

    def close(self) -> None:
        """Delete readers, then writers, then the participant (and its topics with it).

        cyclonedds-python deletes an entity in its __del__ (dds_delete, once: a second
        call finds it gone), so calling that fixes the order."""
        for e in [*self._readers, *self._writers]:
            e.__del__()
        self._readers.clear()
        self._writers.clear()
        self._clients.clear()
        self.dp.__del__()
        self._topics.clear()

    @staticmethod
    def wait_matched(endpoint, timeout: float = DISCOVERY_TIMEOUT) -> None:
        deadline = time.monotonic() + timeout
        getter = (
            endpoint.get_matched_subscriptions
            if isinstance(endpoint, DataWriter)
            else endpoint.get_matched_publications
        )
        while time.monotonic() < deadline:
            if getter():
                return
            time.sleep(0.02)
        raise AssertionError(f"no DDS match for {endpoint.topic.name} within {timeout} s")

    @staticmethod
    def take(reader: DataReader, timeout: float, until=None, max_samples: int = 100000):
        """Samples taken until `until(sample)` is true (returned last) or the timeout."""
        out = []
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for s in reader.take(N=256):
                if s is None or not hasattr(s, "__dataclass_fields__"):
                    continue
                out.append(s)
                if until is not None and until(s):
                    return out
                if len(out) >= max_samples:
                    return out
            time.sleep(0.005)
        if until is not None:
            raise AssertionError(f"condition not met within {timeout} s ({len(out)} samples)")
        return out

    def service(self, name: str, req_type, resp_type, fresh: bool = False):
        """The request writer and reply reader of service `name`, matched to the node.

        A client keeps its endpoints (as an rclpy client does): they are created and
        matched once per participant, on one Topic per name, and reused by every call.
        `fresh=True` makes a new pair on the same topics, as a short-lived client does."""
        if not fresh and name in self._clients:
            return self._clients[name]
        w = self.writer(f"{name}Request", req_type, reliable_qos(), prefix="rq")
        r = self.reader(f"{name}Reply", resp_type, reliable_qos(), prefix="rr")
        self.wait_matched(w)
        self.wait_matched(r)
        if not fresh:
            self._clients[name] = (w, r)
        return w, r

    def call(self, name: str, req_type, resp_type, timeout: float = 10.0, fresh: bool = False,
             **fields):
        """Call a ROS 2 service the way rmw_cyclonedds does."""
        w, r = self.service(name, req_type, resp_type, fresh=fresh)
        self._seq += 1
        seq = self._seq
        w.write(req_type(client_guid=self.guid, sequence_number=seq, **fields))
        replies = self.take(
            r,
            timeout,
            until=lambda s: s.client_guid == self.guid and s.sequence_number == seq,
        )
        if fresh:  # a short-lived client: its endpoints go (its topics stay, see above)
            for e, owner in ((r, self._readers), (w, self._writers)):
                owner.remove(e)
                e.__del__()
        return replies[-1]


@pytest.fixture
def ros(domain_id):
    r = Ros(domain_id)
    yield r
    r.close()


def pose_msg(x, y, z, q=(0.0, 0.0, 0.0, 1.0), frame="world", sec=0, nanosec=0):
    return rt.PoseStamped(
        header=rt.Header(stamp=rt.Time(sec=sec, nanosec=nanosec), frame_id=frame),
        pose=rt.Pose(
            position=rt.Point(x=x, y=y, z=z),
            orientation=rt.Quaternion(x=q[0], y=q[1], z=q[2], w=q[3]),
        ),
    )


def finite(*values) -> bool:
    return all(math.isfinite(v) for v in values)


def markers_finite(ma) -> bool:
    for m in ma.markers:
        for p in m.points:
            if not finite(p.x, p.y, p.z):
                return False
        for c in m.colors:
            if not finite(c.r, c.g, c.b, c.a):
                return False
        if not finite(m.scale.x, m.scale.y, m.scale.z, m.pose.position.x):
            return False
    return True


def set_params(ros, node: str = "/developable_sim", **values):
    """Call `<node>/set_parameters` as `ros2 param set` does (`a__b` names `a.b`);
    returns the SetParametersResult of each, in order."""
    bool_, double, string = 1, 3, 4
    params = []
    for name, v in values.items():
        name = name.replace("__", ".")
        if isinstance(v, bool):
            pv = rt.ParameterValue(type=bool_, bool_value=v)
        elif isinstance(v, float):
            pv = rt.ParameterValue(type=double, double_value=v)
        else:
            pv = rt.ParameterValue(type=string, string_value=v)
        params.append(rt.Parameter(name=name, value=pv))
    r = ros.call(
        f"{node}/set_parameters",
        rt.SetParametersRequest,
        rt.SetParametersResponse,
        parameters=params,
    )
    return r.results
