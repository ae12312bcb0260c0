"""EN 50317 statistics and the penalty law."""

import numpy as np
import pytest

from pantocosim.core.errors import ParameterError
from pantocosim.interaction.penalty_contact import PenaltyContact
from pantocosim.master.results.statistics import (contact_statistics, force_spectrum, lowpass,
                                          window_mask)


def _signal():
    dt = 1e-3
    t = np.arange(0, 10, dt)
    x = 50.0 + 83.33 * t  # 300 km/h
    f = 150 + 30 * np.sin(2 * np.pi * 2.0 * t) + 20 * np.sin(2 * np.pi * 60.0 * t)
    return dt, t, x, f


def test_lowpass_keeps_band_and_removes_high_frequencies():
    dt, t, x, f = _signal()
    g = lowpass(f, dt)
    core = slice(2000, 8000)
    expected = 150 + 30 * np.sin(2 * np.pi * 2.0 * t)
    assert np.max(np.abs(g[core] - expected[core])) < 0.05  # 60 Hz gone, 2 Hz kept, no lag


def test_statistics_of_known_signal():
    dt, t, x, f = _signal()
    window = (200.0, 700.0)
    s = contact_statistics(t, f, x, window)
    assert s.mean_n == pytest.approx(150.0, abs=0.05)
    assert s.std_n == pytest.approx(30 / np.sqrt(2), rel=2e-3)
    assert s.stat_max_n == pytest.approx(s.mean_n + 3 * s.std_n)
    assert s.stat_min_n == pytest.approx(s.mean_n - 3 * s.std_n)
    assert s.max_n == pytest.approx(180.0, abs=0.1)
    assert s.min_n == pytest.approx(120.0, abs=0.1)
    assert s.loss_of_contact_percent == 0.0
    mask = window_mask(x, *window)
    assert s.samples == mask.sum()


def test_loss_of_contact_and_support_uplift():
    dt, t, x, f = _signal()
    f = f.copy()
    f[(t > 4.0) & (t < 4.1)] = 0.0  # 0.1 s without contact inside the window
    uplift = np.column_stack([0.01 * np.sin(t) ** 2, 0.05 * np.ones_like(t)])
    s = contact_statistics(t, f, x, (200.0, 700.0), uplift, np.array([300.0, 900.0]))
    in_window = ((x >= 200) & (x <= 700)).sum()
    assert s.loss_of_contact_percent == pytest.approx(100 * 99 / in_window, rel=0.02)
    inside = (x >= 200) & (x <= 700)
    assert s.max_uplift_at_support_m == pytest.approx(np.max(0.01 * np.sin(t[inside]) ** 2))


def test_window_outside_run_is_an_error():
    dt, t, x, f = _signal()
    with pytest.raises(ParameterError, match="analysis window"):
        contact_statistics(t, f, x, (2000.0, 2500.0))


def test_spectrum_peaks():
    dt, t, x, f = _signal()
    freqs, amp = force_spectrum(t, f)
    i2 = np.argmin(abs(freqs - 2.0))
    assert amp[i2] == pytest.approx(30.0, rel=0.02)
    assert freqs[np.argmax(amp)] == pytest.approx(2.0, abs=0.1)


def test_penalty_law():
    c = PenaltyContact(50_000.0)
    assert c.force(5.301, 5.300) == pytest.approx(50.0)
    assert c.force(5.299, 5.300) == 0.0
    f, dz, dv = PenaltyContact(50_000.0, 100.0).force_and_derivatives(5.301, 5.3, 0.0, 2.0)
    assert f == 0.0 and dz == 0.0  # damping pulls the force below zero: released
    with pytest.raises(ParameterError, match="contact.stiffness"):
        PenaltyContact(-1.0)
