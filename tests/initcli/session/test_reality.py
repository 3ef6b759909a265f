"""Sessions in a site built unlike its model (issue 11): the session may fail, it may never claim a
wrong pose. Each case is a world a real site produces: every door shifted, a hoarding across the
corridor, a poster detected as a door right beside a real door."""

from __future__ import annotations

import dataclasses

import pytest

from bimtools.site.load import Site
from initcli.config import SessionConfig, load_config
from initcli.config.building import prepare_site
from initcli.core.geometry.se2 import Pose2D
from initcli.io.detection_log import State
from initcli.session.simulated import sim_session
from initcli.sim.synthetic_log import SimFeature
from initcli.verify.registration import DECIDED_BY_REGISTRATION
from tests.helpers import SAMPLES

WRONG_M = 2.0  # a claimed pose this far from the truth is a confident wrong result


@pytest.fixture(scope="module")
def block_a(tmp_path_factory: pytest.TempPathFactory) -> tuple[SessionConfig, Site]:
    config = load_config(SAMPLES / "block_a.site.yaml")
    return config, prepare_site(config, tmp_path_factory.mktemp("block_a"))


def _construction(name: str, tmp_path_factory: pytest.TempPathFactory) -> tuple[SessionConfig, Site]:
    config = load_config(SAMPLES / f"{name}.site.yaml", reality="construction")
    return config, prepare_site(config, tmp_path_factory.mktemp(name))


@pytest.fixture(scope="module")
def ntu_construction(tmp_path_factory: pytest.TempPathFactory) -> tuple[SessionConfig, Site]:
    """ntu_hallway under the construction profile, its site prepared once for the module."""
    return _construction("ntu_hallway", tmp_path_factory)


@pytest.fixture(scope="module")
def block_b_construction(tmp_path_factory: pytest.TempPathFactory) -> tuple[SessionConfig, Site]:
    """block_b under the construction profile, its site prepared once for the module."""
    return _construction("block_b", tmp_path_factory)


def with_sim(config: SessionConfig, **as_built: float) -> SessionConfig:
    sim = dataclasses.replace(config.sim, as_built=dataclasses.replace(config.sim.as_built, **as_built))
    return dataclasses.replace(config, sim=sim)


def with_never_seen(config: SessionConfig, share: float) -> SessionConfig:
    """The same session with ``share`` of the real features never seen by the detector."""
    detector = dataclasses.replace(config.sim.detector, never_seen=share)
    return dataclasses.replace(config, sim=dataclasses.replace(config.sim, detector=detector))


def with_active_exploration(config: SessionConfig, active: bool) -> SessionConfig:
    return dataclasses.replace(config, exploration=dataclasses.replace(config.exploration, active=active))


def assert_never_wrong(result) -> None:
    if result.success:
        assert result.pose is not None and result.truth_pose is not None
        assert result.pose.distance_to(result.truth_pose) < WRONG_M, result.reason
    else:
        assert result.reason  # an honest failure says why


@pytest.mark.parametrize("seed", [2, 5])
def test_every_door_shifted_half_a_metre(block_a, seed: int) -> None:
    config, site = block_a
    built = sim_session(with_sim(config, door_shift=0.5), site, seed)
    assert built.setup.as_built is not None and built.setup.as_built.changes["shifted_doors"] > 5
    assert_never_wrong(built.session.run())


def test_hoardings_across_the_corridors(block_a) -> None:
    config, site = block_a
    built = sim_session(with_sim(config, hoarding=6.0), site, 3)
    assert built.setup.as_built is not None and built.setup.as_built.hoardings
    assert_never_wrong(built.session.run())


def test_a_poster_seen_as_a_door_right_beside_a_real_door(block_a) -> None:
    config, site = block_a
    start = Pose2D(10.0, 11.0, 0.0)
    built = sim_session(config, site, 3, start)
    detector = built.setup.driver.detector.__self__  # the simulated detector's features
    doors = [f for f in detector.features if f.cls == "door"]
    near = min(doors, key=lambda f: (f.x - start.x) ** 2 + (f.y - start.y) ** 2)
    along = (-near.norm_y, near.norm_x)
    detector.features.append(
        SimFeature(
            "poster", "door", near.x + 1.2 * along[0], near.y + 1.2 * along[1], near.norm_x, near.norm_y
        )
    )
    result = built.session.run()
    assert_never_wrong(result)


def test_a_claim_with_rivals_sends_the_robot_where_they_disagree(ntu_construction) -> None:
    """ntu_hallway under construction, seed 2 (a start where it happens; 26 until the local map's
    openings had to be three cells wide): a unique match that needed an outlier has rivals once more
    outliers are allowed; instead of wall following on, the session validates the claim and its
    rivals (§3.3.4's active exploration), and never claims a wrong pose. Without the lidar
    registration, which decides this session first (the open doors tell it)."""
    config, site = ntu_construction
    config = with_active_exploration(doors_only(config), True)
    built = sim_session(config, site, 2)
    result = built.session.run()
    assert_never_wrong(result)
    states = [{**r.data, "t": r.t} for r in built.session.perception.log.records if isinstance(r, State)]
    rivalled = [i for i, s in enumerate(states) if str(s.get("why", "")).startswith("unique match has")]
    assert rivalled, "no claim with rivals in this session any more: pick another seed"
    validated = [
        i
        for i in rivalled
        if i + 1 < len(states) and "target" in states[i + 1] and states[i + 1]["t"] == states[i]["t"]
    ]
    assert validated, [states[i : i + 2] for i in rivalled]
    assert all(states[i + 1]["state"] == "active" for i in validated)


def test_a_turned_lobby_is_not_claimed_when_doors_are_far_off_their_place(ntu_construction) -> None:
    """ntu_hallway under construction with doors built sigma 0.6 m off their place (twice the
    profile's), seed 16: five features fit the point-symmetric lift lobby turned 177 degrees within
    Eq. 8's tolerance while the true place, 0.66 m and 9 degrees from where the match puts it, falls
    outside it. A claim must stay unique with alpha 1.5 times wider, its rivals' scans may move them
    twice as far: the session fails honestly instead of claiming the turned lobby."""
    config, site = ntu_construction
    built = sim_session(with_sim(config, door_shift=0.6), site, 16)
    assert_never_wrong(built.session.run())


def test_a_place_the_lidar_picks_out_of_several_gets_the_wide_rival_search(ntu_construction) -> None:
    """ntu_hallway under construction with a fifth of the features never seen (twice the
    profile's), seed 5 (15 until the local map's openings had to be three cells wide; there, after 10
    features three hypotheses were left, all 11-28 m from the truth, and the lidar along the path
    favoured the place turned 179 degrees: the building is point-symmetric, so its scans fit every
    window as well as the true place would, and with Eq. 8's tolerance as it is the true place, its
    doors built off their place, was not among the claim's rivals). A place the lidar picked out of
    several gets the wider rival search (alpha 1.5x, as claims on few features do): the session
    never claims a wrong pose. Without the lidar registration, which decides this session first (the
    open doors tell it)."""
    config, site = ntu_construction
    config = doors_only(config)
    built = sim_session(with_never_seen(config, 0.2), site, 5)
    assert_never_wrong(built.session.run())
    assert any("the lidar along the path favours" in n for n in _notes(built.session)), (
        "no place picked out by the lidar any more: pick another seed"
    )


def test_a_rival_that_passed_the_checks_is_still_looked_for_after_more_features(ntu_construction) -> None:
    """ntu_hallway under construction without active exploration, seed 97: a claim on 6 features is
    held back by the true place as a rival that passes the checks; one feature later the claim has 7
    matched features, so alpha is no longer widened for its rival search, and the true place (doors
    built off their place) drops out of it. The claim, 10 m along the periodic corridor, would pass
    every check. Claims within 10 m of one held back by credible rivals get the wide rival search:
    the session fails honestly instead. Without the lidar registration, which decides this session
    first (the open doors tell it)."""
    config, site = ntu_construction
    config = with_active_exploration(doors_only(config), False)
    built = sim_session(config, site, 97)
    result = built.session.run()
    assert_never_wrong(result)
    assert built.session.claims.doubted_at is not None, (
        "no claim held back by a credible rival any more: pick another seed"
    )


def without_track(config: SessionConfig) -> SessionConfig:
    """The same session without the lidar along the path (``verification.track_m: 0``)."""
    return dataclasses.replace(config, verification=dataclasses.replace(config.verification, track_m=0.0))


def doors_only(config: SessionConfig) -> SessionConfig:
    """The same session without the lidar registration (``registration.enabled: false``): the
    camera's features decide, as in the paper."""
    return dataclasses.replace(config, registration=dataclasses.replace(config.registration, enabled=False))


def _notes(session) -> list[str]:
    return [str(r.data.get("why", "")) for r in session.perception.log.records if isinstance(r, State)]


@pytest.mark.parametrize(
    ("sample", "seed", "note", "failure"),
    [
        pytest.param("ntu", 40, "or by the lidar along the path", "without a unique match", id="rivals"),
        pytest.param(
            "block_b", 51, "the lidar along the path favours hypothesis", "hypotheses", id="several"
        ),
        pytest.param(
            "block_b",
            94,
            "3 hypotheses, 1 pass the checks: the lidar along the path",
            "hypotheses",
            id="alone",
        ),
    ],
)
def test_the_scans_along_the_path_decide_what_the_recent_scans_cannot(
    request: pytest.FixtureRequest, sample: str, seed: int, note: str, failure: str
) -> None:
    """Three starts under construction that only the lidar along the path decides; without it each
    drives 150 m and fails.

    - ``rivals``, ntu_hallway seed 40: after 101 s the lidar favours one of 3 hypotheses (1 passes
      the recent checks), and of its 14 rivals with an outlier more along the periodic corridors,
      those that pass them too trail it by an outlier and the scan fit or by the scans along the
      path: the session claims the right place (0.06 m off).
    - ``several``, block_b seed 51: after 118 s, 8 hypotheses, 2 of which pass the recent checks;
      the scans along the path fit every window of one of them and plainly not the others. It is
      checked as a unique match (rival search included) and claimed, right.
    - ``alone``, block_b seed 94: for 29 s three hypotheses on 9 features, the right one alone
      passing the recent checks. It outranks the two others by the path's scans (each searched wide
      first) and is claimed (0.02 m off).

    (Seeds picked again when the simulated workers learnt to give way: the worlds changed.)

    The lidar registration is off: it would claim some of these sessions before the doors do.
    """
    config, site = request.getfixturevalue(f"{sample}_construction")
    config = doors_only(config)
    built = sim_session(config, site, seed)
    result = built.session.run()
    assert result.success, result.reason
    assert_never_wrong(result)
    assert any(note in n for n in _notes(built.session))
    alone = sim_session(without_track(config), site, seed).session.run()
    assert not alone.success and failure in alone.reason


def test_hypotheses_left_undecided_are_judged_again_as_the_path_goes_on(ntu_construction) -> None:
    """ntu_hallway under construction, seed 2: after the 6th feature the unique match is held back
    by rivals that pass the checks too, and the scans of the path cannot yet tell them apart; no
    feature follows for 24 s. Matched and judged again every 10 m of travel, the match is decided
    once the path has gone on: the right place is claimed on the same 6 features. Without the lidar
    registration, which decides this session first (the open doors tell it)."""
    config, site = ntu_construction
    built = sim_session(doors_only(config), site, 2)
    result = built.session.run()
    assert result.success, result.reason
    assert_never_wrong(result)
    steps = [(m.t, m.features) for m in result.match_steps]
    again = [t for (t, n), (_, before) in zip(steps[1:], steps, strict=False) if n == before]
    assert again, steps  # match steps without a new feature
    assert result.match_steps[-1].features == result.match_steps[-2].features  # claimed at one of them


def test_a_true_place_failing_the_recent_checks_keeps_a_turned_place_from_being_favoured(
    block_b_construction,
) -> None:
    """block_b under construction with hoardings twice the profile's, seed 5: after 90 s without a
    new feature four hypotheses are left; the true place is found 1.5 m off its pose and fails the
    recent scan fit (0.53), the place turned 179 degrees 7 m away fits the scans along the path
    best of those that pass. Judged only against those that pass, the turned place was claimed. The
    true place, its newest window searched wide, keeps it out: the session claims right, later."""
    config, site = block_b_construction
    result = sim_session(with_sim(config, hoarding=2.0), site, 5).session.run()
    assert_never_wrong(result)
    assert result.success, result.reason


@pytest.fixture(scope="module")
def block_a_construction(tmp_path_factory: pytest.TempPathFactory) -> tuple[SessionConfig, Site]:
    """block_a under the construction profile, its site prepared once for the module."""
    return _construction("block_a", tmp_path_factory)


def test_a_claim_that_explains_every_detection_still_has_its_rivals_checked(block_a_construction) -> None:
    """A unique match with no outlier must stay unique with one more outlier allowed
    (``verification.rival_outliers: 1``): on a site as built the true place can need an outlier
    (a door built off its place) while a place one door along explains every detection (a real
    Revit model, Jesse.1, as built: claimed 3.0 m off with 0 outliers, the true place one outlier
    behind). block_a under construction, seed 6: such a claim meets rivals that pass the checks,
    is held back, and the session initialises at the right place later. The lidar registration is
    off (it places this robot before the doors do)."""
    config, site = block_a_construction
    assert config.verification.rival_outliers == 1
    built = sim_session(doors_only(config), site, 6)
    result = built.session.run()
    held = [n for n in _notes(built.session) if "1 more outlier(s) allowed (the claim has 0 outlier(s)" in n]
    assert held, _notes(built.session)
    assert result.success and result.pose is not None and result.truth_pose is not None
    assert result.pose.distance_to(result.truth_pose) < 0.5


@pytest.mark.parametrize(
    ("seed", "variant"),
    [
        pytest.param(26, lambda c: with_active_exploration(c, True), id="rivals-sent"),
        pytest.param(15, lambda c: with_never_seen(c, 0.2), id="wide-rival-search"),
        pytest.param(97, lambda c: with_active_exploration(c, False), id="rival-passed"),
        pytest.param(2, lambda c: c, id="judged-again"),
    ],
)
def test_the_camera_scenarios_above_with_the_lidar_registration_on(
    ntu_construction, seed: int, variant
) -> None:
    """The ntu_hallway scenarios above run with the registration off, to reach the camera's rules;
    with it on (as shipped) the lidar claims first, through the open doors, and right."""
    config, site = ntu_construction
    result = sim_session(variant(config), site, seed).session.run()
    assert_never_wrong(result)
    assert result.success, result.reason
    assert result.decided_by == DECIDED_BY_REGISTRATION
