"""The exercise: one tick for every mode (live run, links monitor, track replay, session
re-simulation), its pacer, and the listeners a step's events go to."""
