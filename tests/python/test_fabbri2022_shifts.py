"""Issue 23, point 6: the load-dependent phase shifts of the star point's
DFC signal (Fabbri 2022, (3.97)-(3.100)) identified both, on plants whose
4theta shift is not twice the 2theta one.

The plant turns its self and mutual terms apart (machine.star_phi_self,
star_phi_mutual), set here so that its (3.97) shifts at 1.5 A are phi_b =
2 phi_a (today's star_phi_iq), phi_a / 2, 0 and a drawn pair
(fluxdrive.star_shifts.self_mutual_for; the model is checked against the
plant's divider in tests/plant/test_star_point.c). Each case its own noise
seed; each 0.1 s step at 300 rpm covers four electrical turns (every
angle).

Bounds, from the issue's tolerance and (3.102), not from the printout:
* the fitted shifts within 10 % of the plant's shift scale, phi_a within
  0.1 SHIFT_PHI_IQ, phi_b within 0.1 * 2 SHIFT_PHI_IQ (the old test's 10 %
  of the turned axis' shifts);
* to first order in (3.102) a shift error leaves the anisotropy harmonic
  p |d phi_b - 2 d phi_a| i_q of 2 theta, half of it of theta_e: with the
  errors at those bounds, at 1.5 A, HARM_TOL below; the Full IVD on the
  fitted shifts leaves at most the true shifts' harmonic plus that;
* the old procedure (phi_a from the mean error, phi_b = 2 phi_a) leaves
  more than that where (3.102) predicts twice it or more: the test tells
  them apart.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REAL_SIL, REPO_ROOT
from fluxdrive import fabbri2022 as fb
from fluxdrive import star_shifts as ss

pytestmark = pytest.mark.skipif(not REAL_SIL.exists(), reason="fluxdrive-sil not built")

I_REF = fb.PAPER.iq_steps[-1]  # 1.5 A
PA = fb.SHIFT_PHI_IQ  # rad/A
TOL_A, TOL_B = 0.1 * PA, 0.1 * 2.0 * PA
P_T51 = abs(fb.PAPER.p_of(ss.T51["ld"], ss.T51["lq"]))
# deg electrical: p (TOL_B + 2 TOL_A) I_REF / 2
HARM_TOL = float(np.degrees(P_T51 * (TOL_B + 2.0 * TOL_A) * I_REF / 2.0))


CASES = fb.SHIFT_CASES


@pytest.fixture(scope="module")
def out(tmp_path_factory):
    return tmp_path_factory.mktemp("shifts")


@pytest.mark.parametrize("case", list(CASES))
def test_full_ivd_identifies_both_shifts(case, out):
    seed = 1 + list(CASES).index(case)
    pa, pb = CASES[case]
    c = fb.shift_case(REAL_SIL, REPO_ROOT, out, case, pa, pb, seed)
    (ta, tb), (fa, fbb) = c.true, c.fitted
    true, fit, old = c.full_true, c.full_fit, c.full_old
    assert abs(ta - pa) < 1e-9 and abs(tb - pb) < 1e-9  # the plant's keys realise the case
    print(f"{case}: plant self {c.phi_self:.4f} mutual {c.phi_mut:.4f} rad/A; true phi_a "
          f"{ta:.4f} phi_b {tb:.4f}, fitted {fa:.4f} {fbb:.4f} rad/A; 6 f_e harmonic at "
          f"{fit.iq[-1]:.2f} A: fitted {fit.harm_deg[-1]:.3f}, true {true.harm_deg[-1]:.3f} deg "
          f"(bound +{HARM_TOL:.3f}), old {old.harm_deg[-1]:.3f} deg; std {fit.ripple_deg[-1]:.3f}, "
          f"{true.ripple_deg[-1]:.3f}, old {old.ripple_deg[-1]:.3f} deg")
    assert abs(fit.iq[-1] - I_REF) < 0.05
    assert abs(fa - ta) <= TOL_A, (fa, ta)
    assert abs(fbb - tb) <= TOL_B, (fbb, tb)
    # the ripple with the fitted shifts within the true shifts' plus what the
    # tolerated shift error leaves, at every step; the mean within the
    # issue's degree (acceptance 3)
    assert np.all(fit.harm_deg <= true.harm_deg + HARM_TOL), (fit.harm_deg, true.harm_deg)
    assert np.all(np.abs(fit.mean_deg) <= fb.PAPER.full_ivd_tol_deg)
    if abs(tb - 2.0 * ta) * I_REF * P_T51 / 2.0 > 2.0 * np.radians(HARM_TOL):
        # the old procedure leaves more where phi_b is far from 2 phi_a
        assert old.harm_deg[-1] > true.harm_deg[-1] + HARM_TOL, old.harm_deg
