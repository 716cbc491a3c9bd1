"""Frames and units: the ship frame, the ice world, the earth, and conversions at the edges.

Ship (MMG) frame: x forward from midship, y to starboard; heading psi from north,
clockwise. Earth: north, east. Ice world: x east, y north, angles counter-clockwise from
east (as pymunk and the renderer use). The field's south-west corner is the origin of both
earth and world coordinates. ``ship_frame`` holds the one rotation each way.
"""
