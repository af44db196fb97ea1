"""fusetrack.service: the live fusion node (``fusetrack serve``, ``replay``, ``demo --live``).

Sensor nodes send authenticated, versioned messages (:mod:`.schema`, :mod:`.auth`) over UDP,
HTTP, WebSocket or MQTT (:mod:`.mqtt`); the node buffers and aligns them to its fusion ticks
(:mod:`.alignment`), runs the configured tracker (:mod:`.engine`: any filter, the Kushwaha grid through
:mod:`.grid_cells`; several targets through :mod:`.trackers`, the same engine), logs
everything durably (:mod:`.log`) and publishes tracks over REST/WebSocket with a dashboard
(:mod:`.app`). :mod:`.replay` plays a simulated scenario (:mod:`.scenarios`) or a recording into
a running node. See the README's service section.
"""

from .alignment import Aligner as Aligner
from .alignment import Reading as Reading
from .alignment import SensorBuffer as SensorBuffer
from .auth import Frame as Frame
from .auth import FrameFreshness as FrameFreshness
from .auth import SequenceWindow as SequenceWindow
from .auth import bearer_token as bearer_token
from .auth import open_frame as open_frame
from .auth import seal as seal
from .commands import add_live_options as add_live_options
from .commands import add_service_parsers as add_service_parsers
from .commands import run_service_command as run_service_command
from .config import MqttConfig as MqttConfig
from .config import NetworkConfig as NetworkConfig
from .config import SensorConfig as SensorConfig
from .config import TrackerConfig as TrackerConfig
from .config import load_config as load_config
from .config import parse_config as parse_config
from .engine import FusionEngine as FusionEngine
from .engine import build_engine as build_engine
from .log import DurableLog as DurableLog
from .log import replay_log as replay_log
from .log_repair import check_log as check_log
from .log_repair import recover_log as recover_log
from .mqtt import MqttBridge as MqttBridge
from .node import FusionNode as FusionNode
from .schema import MessageBatch as MessageBatch
from .schema import SensorMessage as SensorMessage
from .schema import TrackState as TrackState
from .schema import decode_messages as decode_messages
from .schema import encode_message as encode_message
from .schema import message_json_schema as message_json_schema
