"""Replay of logged voyages through the ice: track logs driven kinematically, session
records re-simulated from their console orders (``icebridge replay``)."""
