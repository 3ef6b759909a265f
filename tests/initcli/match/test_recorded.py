"""The storey and settings a session records in its log's meta record, and ``bim-init match`` taking
them for the options its user did not give."""

from __future__ import annotations

import dataclasses
import json

import pytest

from bimkit.errors import InputError
from initcli.config.matching import MatchOptions
from initcli.core.lidar.registration_params import RegistrationParams
from initcli.io.detection_log import read_log, read_meta
from initcli.io.log_records import NO_CAMERA, NO_MOUNT, Meta
from initcli.io.log_writer import write_log
from initcli.match.recorded import recorded_settings, session_meta_settings


def _meta(**kw) -> Meta:
    return Meta(NO_CAMERA, NO_MOUNT, camera_absent=True, **kw)


def test_the_meta_record_round_trips_and_old_logs_have_none(tmp_path) -> None:
    settings = session_meta_settings(MatchOptions(alpha=0.6), RegistrationParams(window=15.0))
    assert "storey" not in settings["matching"] and "top" not in settings["matching"]
    assert settings["matching"]["alpha"] == 0.6 and settings["registration"]["window"] == 15.0
    path = tmp_path / "log.jsonl"
    write_log(path, [_meta(storey="Level 2", settings=settings)])
    meta = read_log(path).meta
    assert meta.storey == "Level 2" and meta.settings == json.loads(json.dumps(settings))
    assert read_meta(path) == meta
    write_log(path, [_meta()])
    line = json.loads(path.read_text())
    assert "storey" not in line and "settings" not in line
    assert read_log(path).meta.storey is None and read_log(path).meta.settings is None


@pytest.mark.parametrize(
    ("field", "value", "fragment"),
    [("storey", 3, "'storey' must be"), ("settings", {"matching": 1}, "'settings' must be")],
)
def test_a_bad_field_is_refused(tmp_path, field, value, fragment) -> None:
    path = tmp_path / "log.jsonl"
    path.write_text(json.dumps({"type": "meta", "version": 1, "camera_absent": True, field: value}) + "\n")
    with pytest.raises(InputError, match=fragment):
        read_log(path)
    assert read_meta(path) is None


def test_recorded_settings_fill_what_the_user_did_not_give() -> None:
    settings = session_meta_settings(
        MatchOptions(alpha=0.6, beta=10.0), RegistrationParams(enabled=False, window=15.0)
    )
    meta = _meta(storey="Level 2", settings=settings)
    got = recorded_settings(meta, MatchOptions(), set(), "log")
    assert got.options.storey == "Level 2" and got.options.alpha == 0.6 and not got.options.registration
    assert got.registration == RegistrationParams(enabled=False, window=15.0)
    assert got.note == "storey Level 2 and settings from the session's log"
    # the user's options win
    mine = MatchOptions(storey="Level 1", beta=20.0, registration=True)
    got = recorded_settings(meta, mine, {"storey", "beta", "registration"}, "log")
    assert (got.options.storey, got.options.alpha, got.options.beta) == ("Level 1", 0.6, 20.0)
    assert got.registration.enabled and got.registration.window == 15.0
    assert got.note == "settings from the session's log"
    # every storey searched by the session
    got = recorded_settings(_meta(settings=settings), MatchOptions(), set(), "log")
    assert got.options.storey is None
    assert got.note == "settings from the session's log; every storey searched, as it did"


def test_a_log_without_them_leaves_the_options_alone() -> None:
    options = MatchOptions(alpha=0.7)
    for meta in (None, _meta()):
        got = recorded_settings(meta, options, set(), "log")
        assert got.options is options and got.note is None
        assert got.registration == RegistrationParams(enabled=True)


@pytest.mark.parametrize(
    "settings",
    [{"matching": {"alpha": -1}}, {"matching": {"pose_method": "x"}}, {"registration": {"window": "far"}}],
)
def test_bad_recorded_settings_name_the_log(settings) -> None:
    with pytest.raises(InputError, match="session.jsonl: the settings its meta record holds"):
        recorded_settings(_meta(settings=settings), MatchOptions(), set(), "session.jsonl")


def test_unknown_recorded_settings_are_ignored() -> None:
    meta = _meta(settings={"matching": {"alpha": 0.5, "later": 1}, "registration": {"later": 2}, "x": {}})
    got = recorded_settings(meta, MatchOptions(), set(), "log")
    assert got.options == dataclasses.replace(MatchOptions(), alpha=0.5)
