"""fit_modes: the pole-residue fit against scipy's nonlinear least squares
on the same weighted problem, on Welch FRFs of a simulated record, and bad
input raised with its message."""

import numpy as np
import pytest
from scipy.optimize import least_squares

import splinewatch


def _pole(f, zeta):
    w = 2 * np.pi * f
    return complex(-zeta * w, w * np.sqrt(1 - zeta * zeta))


def _model(f, modes, residues, constants):
    """Σ_m A/(s−λ) + Ā/(s−λ̄) + c per function (rows)."""
    s = 2j * np.pi * f
    out = np.tile(np.asarray(constants, dtype=complex)[:, None], (1, len(f)))
    for (fm, zm), a in zip(modes, np.asarray(residues).T):
        lam = _pole(fm, zm)
        out += a[:, None] / (s - lam) + np.conj(a)[:, None] / (s - np.conj(lam))
    return out


TRUTH = [(3.8, 0.12), (4.3, 0.08)]
RESIDUES = np.array([[10 + 3j, 5 - 2j], [7 - 1j, -6 + 1j], [2 + 0j, 10 + 0j]])
CONSTANTS = [1 - 0.1j, 2 - 0.1j, 3 - 0.1j]


def _noisy_functions(seed=3):
    f = np.linspace(2.0, 6.0, 81)
    clean = _model(f, TRUTH, RESIDUES, CONSTANTS)
    sigma = 0.03 * np.abs(clean) + 0.05
    rng = np.random.default_rng(seed)
    noise = (rng.standard_normal(clean.shape) + 1j * rng.standard_normal(clean.shape)) * sigma / np.sqrt(2)
    return f, clean + noise, sigma


def test_fit_modes_is_scipys_weighted_least_squares_optimum_with_its_covariance():
    """Both minimise the same weighted cost, scipy over poles, residues and
    constants together (trust-region reflective, started at the truth),
    splinewatch with the residues projected out (started from its grid):
    the same optimum to 1e-6 relative, and the same Gauss-Newton standard
    deviations of f and ζ (scipy's from its full Jacobian's normal matrix,
    the poles' block of its inverse) to 1 %, the difference being each
    side's Jacobian (analytic here, 2-point differences in scipy)."""
    f, h, sigma = _noisy_functions()
    fitted = splinewatch.fit_modes(f, h, sigma, modes=2)
    n_fun = h.shape[0]

    def residual(p):
        modes = [(p[0], p[1]), (p[2], p[3])]
        a = (p[4 : 4 + 2 * n_fun] + 1j * p[4 + 2 * n_fun : 4 + 4 * n_fun]).reshape(n_fun, 2)
        c = p[4 + 4 * n_fun : 4 + 5 * n_fun] + 1j * p[4 + 5 * n_fun :]
        r = (h - _model(f, modes, a, c)) / sigma
        return np.concatenate([r.real.ravel(), r.imag.ravel()])

    start = np.concatenate(
        [
            np.ravel(TRUTH),
            RESIDUES.real.ravel(),
            RESIDUES.imag.ravel(),
            np.real(CONSTANTS),
            np.imag(CONSTANTS),
        ]
    )
    peer = least_squares(residual, start, method="trf", xtol=1e-15, ftol=1e-15, gtol=1e-15)
    assert peer.success
    ours = np.ravel(np.column_stack([fitted.frequency, fitted.damping]))
    np.testing.assert_allclose(ours, peer.x[:4], rtol=1e-6)
    dof = peer.fun.size - peer.x.size
    scale = np.sum(peer.fun**2) / dof
    np.testing.assert_allclose(fitted.residual_scale, scale, rtol=1e-6)
    covariance = scale * np.linalg.inv(peer.jac.T @ peer.jac)
    peer_std = np.sqrt(np.diag(covariance)[:4])
    ours_std = np.ravel(np.column_stack([fitted.frequency_std, fitted.damping_std]))
    np.testing.assert_allclose(ours_std, peer_std, rtol=0.01)
    peer_residues = peer.x[4 : 4 + 2 * n_fun] + 1j * peer.x[4 + 2 * n_fun : 4 + 4 * n_fun]
    np.testing.assert_allclose(fitted.residues, peer_residues.reshape(n_fun, 2).T, rtol=1e-5)
    assert not fitted.at_bound.any()
    assert repr(fitted).startswith(f"FittedModes({fitted.frequency[0]:.3f} Hz ± {fitted.frequency_std[0]:.3f}, ζ ")


def test_fit_modes_on_welch_frfs_weighted_by_their_coherence():
    """Two 5 %-damped modes (1.5 and 4 Hz, exact discrete poles) driven by
    a measured input, 2 % output noise, 480 s: the H1 FRFs of frf() (16 s
    segments), each line weighted by its coherence over the Welch
    averages, give both frequencies within 1 % and damping within 25 %
    (the Hann window's leakage widens the peaks)."""
    from scipy.signal import cont2discrete, lfilter

    fs = 50.0
    rng = np.random.default_rng(5)
    u = rng.standard_normal(int(480 * fs))

    def mode(fm, zeta):
        w = 2 * np.pi * fm
        b, a, _ = cont2discrete(([w * w], [1.0, 2 * zeta * w, w * w]), 1 / fs, method="zoh")
        return lfilter(b[0], a, u)

    y = np.column_stack([mode(1.5, 0.05), mode(4.0, 0.05)]) @ np.array([[1.0, 0.6, -0.4], [0.5, -1.0, 0.9]])
    y += 0.02 * y.std(axis=0) * rng.standard_normal(y.shape)
    f, h, coherence, info = splinewatch.frf(u, y, fs, segment_seconds=16.0, band=(0.5, 6.0), return_info=True)
    assert info["effective_averages"] > 50
    fitted = splinewatch.fit_modes(f, h, coherence=coherence, averages=int(info["effective_averages"]), modes=2)
    np.testing.assert_allclose(fitted.frequency, [1.5, 4.0], rtol=0.01)
    np.testing.assert_allclose(fitted.damping, [0.05, 0.05], rtol=0.25)
    assert np.all(fitted.frequency_std > 0)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda f, h, s: splinewatch.fit_modes(f, h), "give sigma, or coherence and averages"),
        (lambda f, h, s: splinewatch.fit_modes(f, h, s[:, :-1]), "give both as functions × lines"),
        (lambda f, h, s: splinewatch.fit_modes(f[:-1], h, s), "give both as functions × lines"),
        (lambda f, h, s: splinewatch.fit_modes(f, h, 0 * s), "function 0, line 0"),
        (lambda f, h, s: splinewatch.fit_modes(f[::-1], h, s), "frequencies must be positive, finite and increasing"),
        (lambda f, h, s: splinewatch.fit_modes(f[:8], h[:, :8], s[:, :8]), "need more lines than 8"),
        (lambda f, h, s: splinewatch.fit_modes(f, h, coherence=s[:1], averages=10), "give both as functions × lines"),
    ],
)
def test_fit_modes_bad_input_raises_a_value_error_naming_what_was_wrong(call, message):
    f, h, sigma = _noisy_functions()
    with pytest.raises(ValueError) as raised:
        call(f, h, sigma)
    assert message in str(raised.value)
