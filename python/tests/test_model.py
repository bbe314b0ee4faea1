"""Model: modes, FRFs, matrices and both updatings equal the CLI's bit for
bit; the parameters dict drives them; config errors carry the CLI's message."""

import json

import numpy as np
import pytest
import scipy.sparse.linalg

import splinewatch

SINELLO = "config/sinello.toml"


@pytest.fixture(scope="module")
def model(repo):
    return splinewatch.Model.from_config(repo / SINELLO)


def test_modes_are_the_clis_modes(cli, model):
    expected = json.loads(cli("modes", "--config", SINELLO, "--count", "12", "--json").stdout)["modes"]
    modes = model.modes(12)
    assert modes["frequency"].tolist() == [m["frequency_hz"] for m in expected]
    assert modes["kind"] == [m["kind"] for m in expected]
    assert modes["motion"] == [m["motion"] for m in expected]
    shares = [[m["motion_shares"][k] for k in ("longitudinal", "transverse", "vertical", "torsion")] for m in expected]
    assert np.allclose(modes["motion_shares"], shares, rtol=0, atol=1e-12)
    assert modes["supports"] == [s["support"] for s in expected[0]["support_shares"]]
    supports = [[s["share"] for s in m["support_shares"]] for m in expected]
    assert np.allclose(modes["support_shares"], supports, rtol=0, atol=1e-12)
    assert np.allclose(modes["damping"], [m["damping_ratio"] or 0.0 for m in expected], rtol=0, atol=1e-15)
    assert modes["shapes"].shape == (12, 12) and modes["shapes"].dtype == np.float64
    assert modes["damping"].shape == (12,)


def test_frf_is_the_clis_synthetic_frf(cli, model, tmp_path):
    out = tmp_path / "synth.json"
    cli("synth", "--config", SINELLO, "--inputs", "P1", "--outputs", "P2,P3", "--from", "1", "--to", "40",
        "--step", "0.5", "--out", out)
    expected = json.loads(out.read_text())
    f = np.array(expected["frequency_hz"])
    h = model.frf(f, inputs=["P1"], outputs=["P2", "P3"])
    assert h.shape == (2, 1, len(f)) and h.dtype == np.complex128
    for row, entry in enumerate(expected["frfs"]):
        assert h[row, 0].real.tolist() == entry["re"] and h[row, 0].imag.tolist() == entry["im"]
    assert model.synthetic_frf(["P1"], ["P2", "P3"], 1.0, 40.0, 0.5) == out.read_text().strip()


def test_frf_update_is_the_clis_update(cli, repo, tmp_path):
    measured = tmp_path / "measured.json"
    cli("synth", "--config", "config/sinello-truth.toml", "--inputs", "P1", "--outputs", "P2,P3,P5,P8,P11",
        "--noise", "0.02", "--seed", "4", "--out", measured)
    expected = cli("update", "--config", SINELLO, "--frf", measured, "--json").stdout.strip()
    model = splinewatch.Model.from_config(repo / SINELLO)
    update = model.update(frf=measured)
    assert update.to_json() == expected
    assert model.parameters == update.values  # applied: the next update is warm-started
    assert update.converged and update.iterations > 0
    truth = splinewatch.Model.from_config(repo / "config/sinello-truth.toml").parameters
    for name in ["west.k1", "east.k2"]:
        assert abs(update.values[name] - truth[name]) < 4 * update.std[name]


def test_modal_update_takes_identified_modes_as_the_cli_does(cli, repo, ambient, tmp_path):
    modes_file = tmp_path / "modes.json"
    cli("oma", "--config", "config/sinello-ambient.toml", ambient, "--out", modes_file)
    expected = cli("update", "--config", "config/sinello-ambient.toml", "--modes", modes_file, "--json").stdout.strip()
    model = splinewatch.Model.from_config(repo / "config/sinello-ambient.toml")
    update = model.update(modes=modes_file, apply=False)
    assert update.to_json() == expected
    assert update.pairs and all(0.9 < mac <= 1.0 for _, _, mac in update.pairs)
    # The Modes object of splinewatch.oma is a modes file too.
    data = np.column_stack([c.data for c in splinewatch.read_recording(ambient).values()])
    names = list(splinewatch.read_recording(ambient))
    identified = splinewatch.oma(data, 256.0, band=(0.5, 80.0), sensors=names)
    assert model.update(modes=identified, apply=False).converged


def test_changing_a_parameter_changes_the_modes(repo):
    m = splinewatch.Model.from_config(repo / SINELLO)
    before = m.modes(8)["frequency"]
    for name in m.parameters:
        if name.endswith(".k2") or name.endswith(".k3"):
            m.parameters[name] *= 0.5
    after = m.modes(8)["frequency"]
    assert np.all(after[3:] < before[3:])  # softer supports: lower bending frequencies
    m.parameters["nonsense"] = 1.0
    with pytest.raises(KeyError, match="unknown parameters \\['nonsense'\\]"):
        m.modes(3)


def test_matrices_assemble_k_as_eq_23_and_give_the_models_frequencies(model):
    mats = model.matrices()
    k, kf, m = mats["K"], mats["K_f"], mats["M"]
    n = mats["index"]["free_dofs"]
    assert k.shape == kf.shape == m.shape == (n, n)
    total = kf.copy()
    for p in mats["index"]["parameters"]:
        factor = p["value"] - 1.0 if p["kind"] == "stiffness_field" else p["value"]
        total = total + factor * mats["dK"][p["name"]]
    assert abs(total - k).max() <= 1e-9 * abs(k).max()
    # The lowest bending frequencies from scipy's eigsh on (K, M), shift-invert near 10 Hz.
    values = scipy.sparse.linalg.eigsh(k.tocsc(), k=6, M=m.tocsc(), sigma=(2 * np.pi * 10.0) ** 2,
                                       return_eigenvectors=False)
    f_scipy = np.sort(np.sqrt(np.abs(values)) / (2 * np.pi))
    f_model = model.modes()["frequency"]
    elastic = f_scipy[f_scipy > 1.0]
    assert len(elastic) >= 3
    for f in elastic:
        # model.modes() solves the dense assembly, the matrices are the sparse
        # one's: 2e-8 apart measured (the sparse path alone agrees with eigsh
        # to 1e-9 in ω², tests/integration/matrices.rs)
        assert np.min(np.abs(f_model - f)) / f < 1e-6


def test_config_errors_carry_the_clis_message(cli, repo, model, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text((repo / SINELLO).read_text().replace(
        "density = 975.0", "density = -1.0"))
    stderr = cli("check-config", bad, check=False).stderr
    with pytest.raises(ValueError) as raised:
        splinewatch.Model.from_config(bad)
    assert stderr.strip() == f"error: {raised.value}"
    with pytest.raises(FileNotFoundError, match="cannot read config file"):
        splinewatch.Model.from_config(tmp_path / "missing.toml")
    with pytest.raises(ValueError, match="frequencies must be positive"):
        model.frf([0.0, 1.0])
    with pytest.raises(ValueError, match="give frf=... or modes=..."):
        model.update()
