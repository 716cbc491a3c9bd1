"""Floes at rest far from the hull leave the dynamic set (static bodies in the engine) and
come back with the pose and momentum they left with: when the hull comes near, and when a
moving floe pushes them."""
import numpy as np
import pytest

from sim_core.fracture.tile_template import FractureSettings, build_tile
from sim_core.frames.hull_contour import waterline_contour
from sim_core.ice import resting
from sim_core.ice.contact_kernels import Contacts
from sim_core.ice.floes import BreakCause, FloeStatus
from sim_core.ice.model import IceDynamicsSettings, compile_ice_model
from sim_core.ice.step import HullMotion, ice_step
from sim_core.ice.tiles import add_hull, break_cells, freeze_tile, new_ice_data, place_tile, thaw_tile

DT = 1 / 30
FAR = HullMotion(np.array([0.0, -9000.0]), 0.0, np.zeros(2), 0.0)


def _broken_strip(colliders: str):
    """A 40 m tile of the given colliders with a strip of cells 12 m wide broken free."""
    settings = IceDynamicsSettings(rest_after_s=0.2, rest_distance=150.0)
    model = compile_ice_model([build_tile(0.5, 5, FractureSettings(tile_side=40.0, colliders=colliders))],
                              settings=settings)
    data = new_ice_data(model, waterline_contour(150.0, 24.0), 0.1)
    rows = data.tiles.rows(place_tile(model, data, 0, (0.0, 0.0)))
    loose = rows[np.abs(data.state.home[rows, 0] - 20.0) < 6.0]
    break_cells(data, loose, BreakCause.HULL)
    return model, data, loose


@pytest.fixture
def rested():
    """A 40 m tile with a broken strip drifting slower than the rest speed, the hull far
    away, stepped until the strip has left the dynamic set."""
    model, data, loose = _broken_strip("sphere")
    st = data.state
    rng = np.random.default_rng(5)
    data.contacts.set_velocity(st, loose, rng.uniform(-0.004, 0.004, (len(loose), 2)),
                               rng.uniform(-1e-4, 1e-4, len(loose)))
    for _ in range(30):
        ice_step(model, data, (FAR,), DT)
    return model, data, loose


def test_resting_floes_keep_pose_and_momentum_and_wake_when_the_hull_comes(rested):
    model, data, loose = rested
    st = data.state
    assert st.resting[loose].all()  # every floe of the strip came to rest
    held = st.xy[loose].copy(), st.yaw[loose].copy(), st.vel[loose].copy(), st.yaw_rate[loose].copy()
    assert np.abs(held[2]).max() > 0.0  # they rest with the small velocity they had
    for _ in range(10):
        ice_step(model, data, (FAR,), DT)
    assert not len(np.intersect1d(data.contacts.read_free(st), loose))  # out of the dynamic set
    for now, then in zip((st.xy[loose], st.yaw[loose], st.vel[loose], st.yaw_rate[loose]), held):
        np.testing.assert_array_equal(now, then)
    near = np.array([20.0, -60.0])  # the hull south of the tile, inside the wake radius, touching nothing
    assert np.hypot(*(st.xy[loose] - near).T).max() < resting.radii(model, data)[1]
    resting.wake_near_hull(model, data, 0, near)
    assert not st.resting[loose].any()
    moving = data.contacts.read_free(st)  # the engine's bodies, read back
    assert set(loose.tolist()) <= set(moving.tolist())
    for now, then in zip((st.xy[loose], st.yaw[loose], st.vel[loose], st.yaw_rate[loose]), held):
        np.testing.assert_array_equal(now, then)  # pose and momentum as they came to rest


def test_a_second_hull_wakes_the_floes_it_comes_near_and_none_rest_near_it(rested):
    """Each hull keeps its own look for resting floes: a second ship's hull coming up to the
    strip wakes it while the first stays far, and floes near it do not go back to rest."""
    model, data, loose = rested
    st = data.state
    assert st.resting[loose].all()
    add_hull(data, waterline_contour(100.0, 16.0), 0.1)
    near = HullMotion(np.array([20.0, -60.0]), 0.5 * np.pi, np.zeros(2), 0.0)  # south of the tile, touching nothing
    ice_step(model, data, (FAR, near), DT)
    assert not st.resting[loose].any()
    for _ in range(30):
        ice_step(model, data, (FAR, near), DT)
    assert not st.resting[loose].any()  # within the rest radius of the second hull


def test_a_moving_floe_that_strikes_a_resting_one_wakes_it(rested):
    model, data, loose = rested
    st = data.state
    striker = loose[np.argmin(st.xy[loose, 1])]  # the southernmost floe of the strip
    others = loose[loose != striker]
    target = others[np.argmin(np.hypot(*(st.xy[others] - st.xy[striker]).T))]
    data.contacts.wake(st, np.array([striker]))
    push = st.xy[target] - st.xy[striker]
    data.contacts.set_velocity(st, np.array([striker]), (push / np.hypot(*push))[None, :] * 1.0, np.zeros(1))
    start = st.xy[target].copy()
    for _ in range(30):
        ice_step(model, data, (FAR,), DT)
        if not st.resting[target]:
            break
    assert not st.resting[target]
    for _ in range(10):
        ice_step(model, data, (FAR,), DT)
    assert np.hypot(*(st.xy[target] - start)) > 0.01  # pushed away, as a floe in the dynamic set


def test_a_steady_push_too_small_for_one_step_adds_up_until_the_floe_wakes(rested):
    model, data, loose = rested
    st = data.state
    striker, target = loose[0], loose[1]
    data.contacts.wake(st, np.array([striker]))  # a moving floe against a resting one
    mass = model.mass[st.gcell[target]]
    each = 0.3 * model.settings.rest_speed * mass  # N s a step: a third of what wakes it at once
    start = st.vel[target].astype(float).copy()
    toward = np.array([1.0, 0.0])
    data.contacts.set_velocity(st, np.array([striker]), 0.5 * toward[None, :], np.zeros(1))  # faster than rest_speed
    push = Contacts(np.array([striker]), np.array([target]), -each * toward[None, :],  # impulse on a; b gets +each
                    toward[None, :], st.xy[target][None, :].copy())  # at its centre: no turn
    steps = 0
    while st.resting[target] and steps < 40:
        resting.wake_struck(model, data, push)
        steps += 1
    assert steps > 1  # not the first push alone
    assert not st.resting[target]  # the pushes added up and woke it
    pair = mass + model.mass[st.gcell[striker]]  # the floe takes its share of a plastic collision's impulse
    np.testing.assert_allclose(st.vel[target], start + steps * each / pair * toward, rtol=1e-5, atol=1e-7)


def test_a_tile_frozen_with_resting_floes_thaws_with_their_pose_and_momentum(rested):
    model, data, loose = rested
    st = data.state
    assert st.resting[loose].all()
    held = st.xy[loose].copy(), st.yaw[loose].copy(), st.vel[loose].copy(), st.yaw_rate[loose].copy()
    tile = int(st.tile[loose[0]])
    cells = loose - data.tiles.rows(tile)[0]
    freeze_tile(data, tile)
    while data.contacts.swaps_pending:  # the resting floes' objects leave the space over the steps
        ice_step(model, data, (FAR,), DT)
    assert not data.contacts.has_tile(tile)
    record = data.frozen[tile][np.searchsorted(data.frozen[tile]["cell"], cells)]
    for now, then in zip((record["xy"], record["yaw"], record["vel"], record["yaw_rate"]), held):
        np.testing.assert_array_equal(now, then)  # frozen: the pose and momentum they rested with
    thaw_tile(model, data, tile)
    back = data.tiles.rows(tile)[cells]
    assert not st.resting[back].any()
    for now, then in zip((st.xy[back], st.yaw[back], st.vel[back], st.yaw_rate[back]), held):
        np.testing.assert_array_equal(now, then)
    steps = 0
    while data.contacts.swaps_pending:
        ice_step(model, data, (FAR,), DT)
        steps += 1
    assert set(back.tolist()) <= set(data.contacts.read_free(st).tolist())  # dynamic bodies again
    drift = np.hypot(*(st.xy[back] - held[0]).T)
    assert drift.max() <= np.hypot(*held[2].T).max() * steps * DT + 1e-6  # moving on from where they froze


def test_floes_come_to_rest_without_contacts_the_engine_would_keep():
    """Broken mesh cells touch one another and the level ice. Chipmunk keeps a contact
    between two static bodies for good and lists it every step, so a floe sheds its
    contacts before it rests: once the strip rests, no contact names a resting floe and
    another resting floe or the level ice."""
    model, data, loose = _broken_strip("mesh")
    st, strip = data.state, set(loose.tolist())

    def static(row: int) -> bool:  # the level ice (an intact cell or its tile), or a resting floe
        return row < 0 or st.status[row] == FloeStatus.INTACT or bool(st.resting[row])

    def strip_contacts() -> tuple[int, int]:
        """The strip's contacts: between two static bodies, and all."""
        con = data.contacts.read_contacts(st)
        pairs = [(a, b) for a, b in zip(con.a.tolist(), con.b.tolist()) if a in strip or b in strip]
        return sum(static(a) and static(b) for a, b in pairs), len(pairs)
    ice_step(model, data, (FAR,), DT)
    assert strip_contacts()[1] > len(loose) // 2  # the strip's floes touch each other and the level ice
    for _ in range(30):
        ice_step(model, data, (FAR,), DT)
    assert st.resting[loose].all()
    assert strip_contacts()[0] == 0


def test_floes_counted_at_rest_again_while_they_shed_rest_once():
    """With steps so long that a floe counts as at rest again within its shedding (0.1 s
    steps, 0.2 s at rest), the step that settles a floe still holds it among the moving
    floes it read before: it must not be taken out of the dynamic set a second time
    (Chipmunk aborts on removing a body twice)."""
    model, data, loose = _broken_strip("sphere")
    for _ in range(30):
        ice_step(model, data, (FAR,), 0.1)
    st = data.state
    assert st.resting[loose].all()
    moving = set(data.contacts.read_free(st).tolist())
    assert not moving & set(loose.tolist())  # each body left the dynamic set, once
