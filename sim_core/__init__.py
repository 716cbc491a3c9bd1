"""IceBridge simulation core: ship model, ice fracture, contact, buoyancy, scene, world step.

No I/O, no GL: every function here takes and returns numpy arrays and plain parameter
objects, so the core runs headless and under test without the bridge node.
"""
