"""The live node fed from recorded files.

`fusetrack serve` runs a *fusion node*: sensor nodes send it readings (over UDP, HTTP or a
WebSocket, each signed with its node's key), it buffers and orders them, fuses them on a fixed
tick with the configured filter and publishes tracks. The same node can be fed a *recording*
— a JSON Lines file with one reading per line, in the node's message schema — to test a
network configuration on logged data before going live, or to re-run a day's data with another
filter.

Over the network that is two commands:

```sh
fusetrack serve --config network.yaml
fusetrack replay recording.jsonl --to udp://127.0.0.1:9000 --config network.yaml --speed inf
```

Here we do the same in-process, with no network at all: the node's rules (authentication
aside) live in `FusionNode`, which the server only wraps. We

1. describe the sensor network in a YAML file (sensors, the nodes that own them, the fusion
   tick and the filter),
2. write a small recording: a microphone array's bearings and a radio tag's position fixes of
   a walking person,
3. feed each line to the node and let it fuse, then read the published tracks.

Run: `python docs/tutorials/06_live_node_from_recordings.py [--quick] [--out DIR]`.
"""

import argparse
import json
import os
import tempfile
from pathlib import Path

import numpy as np

from fusetrack.evaluation import position_error
from fusetrack.evaluation.plots import plot_trajectories
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import Bearing, PositionFix
from fusetrack.service import FusionNode, load_config


def options() -> argparse.Namespace:
    """`--quick` (or `FUSETRACK_QUICK=1`) for a short run; `--out DIR` for the figure."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quick", action="store_true", default=os.environ.get("FUSETRACK_QUICK") == "1"
    )
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "figures")
    return parser.parse_args()


args = options()
duration = 30.0 if args.quick else 60.0
scratch = tempfile.TemporaryDirectory(prefix="fusetrack-tutorial-")  # removed at the end
workdir = Path(scratch.name)

# --- 1. The network ---------------------------------------------------------------------
# Units: metres and seconds; angles in radians or, with the _deg suffix, degrees. The clock
# "data" makes the ticks follow the readings' own times, as a replay needs; "lag" is how long
# the node waits for late readings before it fuses a tick.
network_yaml = """
version: 1
area: [0, 80, 0, 60]
sensors:
  - {id: mic, kind: bearing, position: [0, 0], sigma_deg: 2}
  - {id: tag, kind: position_fix, cov: [[1.0, 0.0], [0.0, 1.0]]}
nodes:
  - {id: array-1, key: tutorial-key-array-1-0001, sensors: [mic]}
  - {id: tag-reader, key: tutorial-key-tag-reader-02, sensors: [tag]}
fusion: {rate_hz: 2, alignment: all, clock: data, lag: 1.0, start: 0.0}
tracker:
  filter: ekf
  motion: {model: constant_velocity, q: 0.1}
  prior_mean: [10, 10, 0, 0]
  prior_std: [5, 5, 1, 1]
"""
(workdir / "network.yaml").write_text(network_yaml)
network = load_config(workdir / "network.yaml")

# --- 2. A recording -------------------------------------------------------------------------
# We simulate a walk and what the sensors would have logged; with real data these lines come
# from your loggers. Each line is one message: which node sent it, its sequence number (per
# node, increasing), the sensor, the time and the reading; `fusetrack.service.message_json_schema()`
# is the full schema.
rng = np.random.default_rng(4)
motion = ConstantVelocity(ndim=2, q=0.005)
mic = Bearing("mic", position=[0.0, 0.0], sigma=np.deg2rad(2.0))
tag = PositionFix("tag", cov=np.eye(2))
x = np.array([12.0, 8.0, 0.8, 0.4])
truth, lines, seq = [], [], {"array-1": 0, "tag-reader": 0}
for k in range(1, int(duration / 0.5) + 1):
    t = 0.5 * k
    x = motion.sample(x, 0.5, rng)
    truth.append((t, *x[:2]))
    seq["array-1"] += 1
    bearing = float(mic.simulate(x, rng)[0])
    lines.append(
        {
            "node": "array-1",
            "seq": seq["array-1"],
            "sensor": "mic",
            "time": t,
            "reading": {"kind": "bearing", "bearing": bearing},
        }
    )
    if k % 4 == 0:  # the tag every 2 s
        seq["tag-reader"] += 1
        fix = [float(v) for v in tag.simulate(x, rng)]
        lines.append(
            {
                "node": "tag-reader",
                "seq": seq["tag-reader"],
                "sensor": "tag",
                "time": t,
                "reading": {"kind": "position_fix", "position": fix},
            }
        )
recording = workdir / "recording.jsonl"
recording.write_text("".join(json.dumps(line) + "\n" for line in lines))
truth = np.array(truth)
print(f"wrote {len(lines)} readings to {recording}; the first two lines:")
print("".join(recording.read_text().splitlines(keepends=True)[:2]), end="")

# --- 3. Feed the node and read its tracks -----------------------------------------------------
# `ingest_payload(bytes, encoding, node)` is what the HTTP endpoint calls once the node's
# bearer token has named the sender: the message is validated against the schema and the
# network (its sensor belongs to that node, the sequence number is new, the value has the right
# size, it is not too late) and accepted or refused with a reason — never an exception.
# `advance()` fuses every tick that is due and returns the published `TrackState`s.
#
# The node's wall clock matters only at the very end: with the data clock the last `lag`
# seconds are fused once no reading has arrived for `idle_flush` wall seconds. We give the
# node a clock we control and move it on at the end instead of waiting.
wall = [0.0]
node = FusionNode(network, wall=lambda: wall[0])
published, refused = [], {}
for line in recording.read_text().splitlines():
    sender = json.loads(line)["node"]
    for outcome in node.ingest_payload(line.encode(), "json", sender):
        if not outcome.accepted:
            refused[outcome.reason] = refused.get(outcome.reason, 0) + 1
    published += node.advance()
wall[0] += network.fusion.idle_flush + 1.0  # the recording has ended: flush the last ticks
published += node.advance()
print(
    f"accepted {sum(node.accepted.values())} readings, refused {refused or 'none'}; "
    f"{len(published)} ticks published"
)

# A bad line is refused with a reason, not a crash: a sequence number the node has seen.
outcome = node.ingest_payload(recording.read_text().splitlines()[0].encode(), "json", "array-1")[0]
print(f"sending the first line again: accepted={outcome.accepted}, reason={outcome.reason!r}")

# Each TrackState has the tick, its time, the fused state and covariance, the position and its
# covariance, and which sensors' readings went in.
last = published[-1]
print(
    f"last tick {last.tick} at t={last.time:.1f} s: position {np.round(last.position, 2)}, "
    f"fused {last.readings} readings from {last.sensors}"
)
times = np.array([s.time for s in published])
positions = np.array([s.position for s in published])
on_truth = np.array([np.interp(times, truth[:, 0], truth[:, i]) for i in (1, 2)]).T
error = position_error(positions, on_truth, [0, 1])
print(f"mean position error of the node's track: {error.mean():.2f} m")

args.out.mkdir(parents=True, exist_ok=True)
plot_trajectories(
    args.out / "06_live_node_from_recordings.png",
    truth[:, 1:],
    {"the node's track (EKF, 2 Hz ticks)": positions},
    sensors=[("mic", mic.position)],
    title="A recording replayed through the fusion node",
)
print(f"figure written to {args.out / '06_live_node_from_recordings.png'}")
scratch.cleanup()
