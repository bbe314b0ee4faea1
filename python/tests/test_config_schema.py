"""The configuration's JSON Schema (`splinewatch config-schema`, the guide's
editor support) accepts every bundled config and catches what the config
loader catches: a misspelled key, a value of the wrong type."""

import json
import pathlib
import tomllib

import jsonschema
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
CONFIGS = sorted([*(REPO / "config").glob("*.toml"), *(REPO / "config/examples").glob("*.toml"), *(REPO / "tests/fixtures").glob("*.toml")])


@pytest.fixture(scope="module")
def validator(cli):
    schema = json.loads(cli("config-schema").stdout)
    committed = json.loads((REPO / "docs/guide/src/reference/splinewatch.schema.json").read_text())
    assert schema == committed
    return jsonschema.Draft202012Validator(schema)


@pytest.mark.parametrize("path", CONFIGS, ids=lambda p: p.name)
def test_every_bundled_config_satisfies_the_schema(validator, path):
    errors = [e.message for e in validator.iter_errors(tomllib.loads(path.read_text()))]
    assert errors == []


def test_the_schema_catches_a_misspelled_key_and_a_wrong_type(validator, cli, tmp_path):
    config = tomllib.loads((REPO / "config/sinello.toml").read_text())
    config["frf"]["segmnt_seconds"] = 4.0
    errors = [e.message for e in validator.iter_errors(config)]
    assert any("segmnt_seconds" in e for e in errors)
    config = tomllib.loads((REPO / "config/sinello.toml").read_text())
    config["schedule"]["min_coherence"] = "high"
    assert list(validator.iter_errors(config))
