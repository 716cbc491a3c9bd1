"""The traffic picture a run starts with, from its config: the AIS logs it names (replayed as
other vessels) and its scripted vessels."""
from __future__ import annotations

import math
from pathlib import Path

from bridge_node.common.errors import UserError
from bridge_node.links.traffic_picture import TrafficPicture, VesselSource
from bridge_node.node.config import DEFAULT_CONFIG, ConfigError, NodeConfig, resolve_path
from bridge_node.replay.inputs import read_text
from bridge_node.replay.sentences import SentenceLog
from bridge_node.replay.settings import ReplaySettings
from bridge_node.traffic.sources import AisLogTraffic, ScriptedTraffic


def read_ais_log(path: Path, where: str, origin: tuple[float, float], replay: ReplaySettings) -> AisLogTraffic:
    """An AIS log as traffic; ConfigError naming ``where`` (file, key and value) if it
    cannot be read or has no other vessel's position reports."""
    if not path.is_file():
        raise ConfigError(f"{where}: no such file ({path})")
    try:
        text = read_text(path)
    except UserError as exc:
        raise ConfigError(f"{where}: {exc}") from None
    log = SentenceLog()
    log.read(str(path), text.splitlines())
    traffic = AisLogTraffic([v for v in log.vessels.values() if v.reports and not v.own], origin, replay)
    if not traffic.paths:
        raise ConfigError(f"{where}: no position reports of other vessels (AIS types 1, 2, 3, 18, 19 as !AIVDM) "
                          "in it")
    return traffic


def traffic_picture(cfg: NodeConfig, config_path: str | Path | None) -> TrafficPicture:
    """The picture with the config's sources: its AIS logs (in their order), then its
    scripted vessels. ConfigError for a log that cannot be used."""
    origin = math.radians(cfg.exercise.origin_latitude_deg), math.radians(cfg.exercise.origin_longitude_deg)
    where = f"{config_path or DEFAULT_CONFIG}: traffic.ais_logs"
    sources: list[VesselSource] = [read_ais_log(resolve_path(config_path, name), f"{where}.{i} = {name!r}", origin,
                                                cfg.replay) for i, name in enumerate(cfg.traffic.ais_logs)]
    if cfg.traffic.vessels:
        sources.append(ScriptedTraffic(cfg.traffic.vessels, origin))
    return TrafficPicture(sources)
