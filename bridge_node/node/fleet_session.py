"""A session record of several own ships re-simulated (issue 31). A run with ``[[ships]]``
records the first ship's links, tick log, commands and save points in its folder, as any
run does, and each other ship's link traffic and tick log in ``ships/<k>/`` (k = 1 for the
first of ``[[ships]]``). Every ship's links are fed back from its own folder, polled and
arbitrated as the run's were, so that each ship gets the orders its own bridge gave.
"""
from __future__ import annotations

from pathlib import Path

from bridge_node.common.errors import UserError
from bridge_node.node.config import NodeConfig
from bridge_node.replay.session import FLEET_FOLDER, RecordedSession, SessionSource, read_session, record_files
from sim_core.world import Controls


def recorded_ships(folder: Path) -> int:
    """The other own ships a session record holds (its ``ships/<k>`` folders)."""
    ships = folder / FLEET_FOLDER
    return len([p for p in ships.iterdir() if p.is_dir()]) if ships.is_dir() else 0


def session_source(cfg: NodeConfig, session: RecordedSession) -> SessionSource:
    """The replay source of a session record on the exercise ``cfg`` (the record's own
    ``node.toml`` for an exact replay): one ship's links, or every ship's. UserError where
    the record and the config have different numbers of ships."""
    held = recorded_ships(session.folder)
    if held != len(cfg.ships):
        raise UserError(f"{session.folder}: a record of {held + 1} own ship(s), replayed on an exercise of "
                        f"{len(cfg.ships) + 1} ([[ships]]); replay it with the config it was made with (its "
                        "node.toml)")
    return FleetSessionSource(cfg, session) if held else SessionSource(cfg.links, cfg.arbitration, session)


class FleetSessionSource(SessionSource):
    """The first ship's links fed from the record's folder, and each other ship's from its
    own; a step's orders are one ``Controls`` per ship. The other ships' alarm changes stay
    with their links (a replay's outputs are the first ship's)."""

    def __init__(self, cfg: NodeConfig, session: RecordedSession) -> None:
        super().__init__(cfg.links, cfg.arbitration, session)
        self.ships = []
        for k, ship in enumerate(cfg.ships, start=1):
            folder = session.folder / FLEET_FOLDER / str(k)
            names = {n for n in record_files().values() if (folder / n).is_file()}
            try:
                recorded = read_session(folder, names, session.period)
            except ValueError as exc:
                raise UserError(f"{folder}: {exc}") from None
            self.ships.append(SessionSource(ship.links, ship.arbitration, recorded))
        self.steps = min([self.steps, *(s.steps for s in self.ships)])  # a run stopped between two ships' lines

    def __enter__(self) -> FleetSessionSource:
        super().__enter__()
        for ship in self.ships:
            ship.__enter__()
        return self

    def __exit__(self, *exc) -> None:
        for ship in self.ships:
            ship.__exit__(*exc)
        super().__exit__(*exc)

    def inputs(self, k: int) -> tuple[list[Controls], list, float]:
        controls, alarms, now = super().inputs(k)
        return [controls, *(ship.inputs(k)[0] for ship in self.ships)], alarms, now
