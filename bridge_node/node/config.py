"""Node configuration: TOML files loaded into typed, validated parameter blocks.

Every error names the file, the key, the bad value and what is allowed; the CLI prints it
and exits non-zero, without a traceback.
"""
from __future__ import annotations

import re
import tomllib
from datetime import datetime, timezone
from collections.abc import Callable
from pathlib import Path
from typing import Literal

from pydantic import Field, ValidationError, field_validator, model_validator

from bridge_node.charts.sigrid3 import read_chart
from bridge_node.control.settings import ControlSettings
from bridge_node.links.registry import LinkSettings
from bridge_node.links.convoy import ConvoySettings
from bridge_node.links.settings import ArbitrationSettings
from bridge_node.node.ship_settings import (SHIP_NAME, OtherShipSettings, ShipChoice, StartSettings, check_fleet,
                                            check_links)
from bridge_node.common.errors import UserError
from bridge_node.common.input_files import TOML_LIMIT, read_input_text
from bridge_node.common.paths import NUL_IN_PATH, expand_user, writable_dir
from bridge_node.common.toml_errors import shown, toml_error
from bridge_node.render.settings import RenderSettings
from bridge_node.render.warp import read_pfm
from bridge_node.replay.settings import ReplaySettings
from bridge_node.station.settings import InstructorSettings
from bridge_node.stream.settings import StreamSettings
from bridge_node.traffic.settings import TrafficSettings
from sim_core.fracture.tile_template import FractureSettings
from sim_core.ice.model import IceDynamicsSettings
from sim_core.material import IceMaterial
from sim_core.params import Params
from sim_core.scene.field import IceFieldSettings
from sim_core.scene.scene import SceneSettings
from sim_core.ship.particulars import ShipParticulars

DEFAULT_CONFIG = Path(__file__).resolve().parents[2] / "config" / "default.toml"


class PathSettings(Params):
    """Where the node keeps its files. Relative paths are relative to the config file."""

    cache_dir: str = Field("~/.cache/icebridge", description="template library")
    session_dir: str = Field("~/.cache/icebridge/sessions", description="session records of link traffic")

    @field_validator("cache_dir", "session_dir")
    @classmethod
    def _no_nul(cls, value: str) -> str:
        if "\0" in value:
            raise ValueError(NUL_IN_PATH)
        return value


class ExerciseSettings(StartSettings):
    """Where the exercise takes place, how the ship starts, and the wind and current at the
    start (the instructor changes them as it runs). The local north/east frame has its
    origin at the ice field's south-west corner, at the given latitude/longitude. Unset
    start positions put the ship one ship length south of the ice edge, on the centre line
    of the middle tile column. The exercise's date and time and its visibility at the start
    are ``render.start_utc`` and ``render.visibility_m``."""

    origin_latitude_deg: float = Field(74.0, ge=-89.0, le=89.0)
    origin_longitude_deg: float = Field(20.0, ge=-180.0, le=180.0)
    wind_speed_kn: float = Field(0.0, ge=0.0, le=100.0, description="true wind at the start, kn")
    wind_from_deg: float = Field(0.0, ge=0.0, lt=360.0, description="where the wind blows from, deg true")
    current_speed_kn: float = Field(0.0, ge=0.0, le=10.0, description="surface current at the start, kn")
    current_to_deg: float = Field(0.0, ge=0.0, lt=360.0, description="where the current sets to, deg true")

    def origin_deg(self) -> tuple[float, float]:
        """The local frame's origin: (latitude, longitude), degrees."""
        return self.origin_latitude_deg, self.origin_longitude_deg


class RealtimeSettings(Params):
    """The real-time loop."""

    rate_hz: float = Field(30.0, ge=5.0, le=120.0, description="world steps per second")
    scheduler: Literal["normal", "fifo"] = Field(
        "fifo", description="the loop thread's CPU scheduling: fifo (Linux's real-time class) puts it before every "
        "normal process; it needs root or CAP_SYS_NICE, and where refused the loop runs normal and says why")
    priority: int = Field(10, ge=1, le=99, description="the loop thread's real-time priority under fifo")


class RunConsoleSettings(Params):
    """The software console that gives a run its orders (``icebridge run``): ``icebridge
    console`` in its own process plays ``script`` over a real link to the node, then holds its
    last orders. The node's end is added to ``links`` as ``console``, first in the arbitration."""

    script: str = Field(min_length=1, description="scenario file: relative to the config file's folder, else "
                        "to config/")
    link: Literal["can", "nmea0183", "modbus"] = Field("can", description="can: slcan on a pty pair; nmea0183: a "
                                                       "pty pair; modbus: TCP on 127.0.0.1 (pty pairs need socat)")


class NodeConfig(Params):
    """The whole node's configuration. ``ice_field`` and ``ship`` are required."""

    ship: ShipChoice
    exercise: ExerciseSettings = ExerciseSettings()
    ice_material: IceMaterial = IceMaterial()
    fracture: FractureSettings = FractureSettings()
    ice_field: IceFieldSettings
    ice_dynamics: IceDynamicsSettings = IceDynamicsSettings()
    scene: SceneSettings = SceneSettings()
    realtime: RealtimeSettings = RealtimeSettings()
    replay: ReplaySettings = ReplaySettings()
    render: RenderSettings = RenderSettings()
    stream: StreamSettings = StreamSettings()
    control: ControlSettings = ControlSettings()
    instructor: InstructorSettings = InstructorSettings()
    links: list[LinkSettings] = Field(default_factory=list)
    arbitration: ArbitrationSettings = ArbitrationSettings()
    traffic: TrafficSettings = TrafficSettings()
    convoy: ConvoySettings | None = None
    paths: PathSettings = PathSettings()
    console: RunConsoleSettings | None = None

    ships: list[OtherShipSettings] = Field(default_factory=list, description="the exercise's other own ships")

    @model_validator(mode="after")
    def _links(self) -> "NodeConfig":
        check_links(self.links, self.arbitration)
        for i, other in enumerate(self.ships):
            check_links(other.links, other.arbitration, f"ships.{i}.")
        check_fleet(self.ship, self.links, self.console is not None, self.ships)
        return self


class ConfigError(UserError):
    """A user's configuration mistake; the message is complete and meant to be printed."""


def _describe(err: dict) -> str:
    key = ".".join(str(p) for p in err["loc"]) or "(top level)"
    kind = err["type"]
    if kind == "missing":
        return f"{key}: required key is missing"
    if kind == "extra_forbidden":
        return f"{key} = {shown(err['input'])}: unknown key (check the spelling)"
    msg = err["msg"].removeprefix("Value error, ")
    if kind == "value_error":
        return f"{key}: {msg}"
    return f"{key} = {shown(err['input'])}: {msg}"


def load_config(path: str | Path | None = None) -> NodeConfig:
    """Read and validate a TOML config (default: config/default.toml). Raises ConfigError.
    The files the config names (a link's, such as a CAN link's DBC; the run console's
    script; a channel's warp grid) are taken from the config file's folder when they are
    there, else from the project's ``config/`` folder, and checked here."""
    path = Path(path) if path is not None else DEFAULT_CONFIG
    cfg = _load_validated(path, NodeConfig)
    links = [link.with_files(_file_finder(path, f"links.{i}.")) for i, link in enumerate(cfg.links)]
    ships = [s.model_copy(update={"links": [link.with_files(_file_finder(path, f"ships.{k}.links.{i}."))
                                            for i, link in enumerate(s.links)]}) for k, s in enumerate(cfg.ships)]
    console = cfg.console and cfg.console.model_copy(
        update={"script": str(_config_file(path, "console.script", cfg.console.script))})
    channels = [c.model_copy(update={"warp": str(_file_finder(path, f"render.channels.{i}.")("warp", c.warp,
                                                                                          read_pfm))})
                if c.warp is not None else c for i, c in enumerate(cfg.render.channels)]
    render = cfg.render.model_copy(update={"channels": channels})
    ice_field = cfg.ice_field
    if ice_field.chart is not None:
        chart = _file_finder(path, "ice_field.")("chart", ice_field.chart, _readable_chart)
        ice_field = ice_field.model_copy(update={"chart": str(chart)})
    return cfg.model_copy(update={"links": links, "ships": ships, "console": console, "render": render, "ice_field": ice_field})


def _readable_chart(path: Path, where: str) -> None:
    """A chart the config names, read once so that its faults show when the config loads."""
    try:
        read_chart(path)
    except UserError as exc:
        raise ConfigError(f"{where}: {exc}") from None


def _config_file(config: Path, key: str, value: str) -> Path:
    """A regular file a config names: absolute, else in the config file's folder, else in
    the project's ``config/``. ConfigError naming the file, key and value otherwise."""
    where = f"{config}: {key} = {value!r}"
    given = expand_user(value, f"{config}: {key}")
    candidates = [given] if given.is_absolute() else [config.resolve().parent / value, DEFAULT_CONFIG.parent / value]
    try:
        path = next((p for p in candidates if p.exists()), None)
    except OSError as exc:  # a name too long...
        raise ConfigError(f"{where}: {exc.strerror or exc}") from None
    if path is None:
        raise ConfigError(f"{where}: no such file (looked in {', '.join(str(p.parent) for p in candidates)})")
    if not path.is_file():
        raise ConfigError(f"{where}: {path} is not a regular file")
    return path


def _file_finder(config: Path, prefix: str) -> Callable[..., Path]:
    """``find(key, value, check=None)`` for a table's ``with_files``: the file ``prefix + key``
    names, resolved as ``_config_file`` does, and checked by ``check(path, where)`` where one
    is given (a check reads the file and raises UserError or ValueError naming ``where``: a
    clear error when the config loads, not when the file is used). ConfigError naming the
    file, key and value for any error."""

    def find(key: str, value: str, check: Callable[[Path, str], None] | None = None) -> Path:
        path = _config_file(config, prefix + key, value)
        if check is not None:
            where = f"{config}: {prefix}{key} = {value!r}"
            try:
                check(path, where)
            except (UserError, ValueError) as exc:
                raise ConfigError(str(exc)) from None
        return path
    return find


def load_ship(name: str, config_path: str | Path | None = None, key: str = "ship.name") -> ShipParticulars:
    """Particulars of the named ship, from ``ships/<name>.toml`` beside the config file, or
    from the built-in ``config/ships``. Raises ConfigError naming the config file and the
    key (or option) the name came from."""
    where = f"{config_path or DEFAULT_CONFIG}: {key} = {name[:80]!r}"
    if not re.fullmatch(SHIP_NAME, name):
        raise ConfigError(f"{where}: a ship name is letters, digits, _ and - only, at most 64 characters")
    folders = [resolve_path(config_path, "ships"), DEFAULT_CONFIG.parent / "ships"]
    for folder in folders:
        path = folder / f"{name}.toml"
        if path.exists():  # a FIFO or device in its place is an error of read_toml, not "unknown"
            return _load_validated(path, ShipParticulars)
    known = sorted({p.stem for f in folders if f.is_dir() for p in f.glob("*.toml")})
    raise ConfigError(f"{where}: unknown ship {name!r}; ships available: {', '.join(known) or 'none'}")


def read_toml(path: Path, what: str) -> tuple[str, dict]:
    """The text of a TOML file and its tables; ConfigError naming the file (``what``: the
    kind of file, for the messages) if it is missing, not a regular file, too large,
    unreadable or not TOML (also TOML that Python cannot take: nested too deep, an integer
    too long; then the line and key are named too)."""
    try:
        text = read_input_text(path, what, TOML_LIMIT)
        return text, tomllib.loads(text)
    except UserError as exc:
        raise ConfigError(str(exc)) from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML: {exc}") from None
    except (RecursionError, ValueError) as exc:  # nested too deep, a too long integer, a bad time zone...
        raise ConfigError(toml_error(path, text, exc)) from None


def _load_validated(path: Path, schema: type[Params]) -> Params:
    _, data = read_toml(path, "config file")
    try:
        return schema.model_validate(data)
    except ValidationError as exc:
        lines = "\n  ".join(_describe(e) for e in exc.errors())
        raise ConfigError(f"{path}: invalid configuration:\n  {lines}") from None


def new_session_dir(cfg: NodeConfig, config_path: str | Path | None) -> Path:
    """A new session record folder under ``paths.session_dir``, named by the UTC time;
    UserError if no files can be written there."""
    root = writable_dir(resolve_path(config_path, cfg.paths.session_dir), f"{config_path or DEFAULT_CONFIG}: "
                        "paths.session_dir")
    return root / datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%SZ")


def resolve_path(config_path: str | Path | None, value: str) -> Path:
    """A path from the config: ~ expanded, relative paths taken from the config's folder."""
    p = expand_user(value, f"{config_path or DEFAULT_CONFIG}: path")
    if p.is_absolute():
        return p
    base = Path(config_path).resolve().parent if config_path else DEFAULT_CONFIG.parent
    return base / p
