"""The modes a run had at one of its samples, as the compiled model takes them: a helper of
the tests that evaluate the model at a run's samples."""

import numpy as np

from scoutsim._core.model import layout as L


def sample_modes(r, n: int, slide_dir: int):
    """(mi, mf, cmd) of sample ``n`` of the run ``r``: its contact and motor-joint modes,
    the sliding direction ``slide_dir`` (+1 or -1) for both toes, the toes' anchors at
    their recorded positions, and the commanded hip torques."""
    mi = np.zeros(L.NMI, dtype=np.int64)
    mf = np.zeros(L.NMF)
    mi[L.MI_CONTACT_B : L.MI_CONTACT_B + 2] = r.modes[n, L.RM_CONTACT_B : L.RM_CONTACT_B + 2]
    mi[L.MI_MOTOR_B : L.MI_MOTOR_B + 2] = r.modes[n, L.RM_MOTOR_B : L.RM_MOTOR_B + 2]
    mi[L.MI_SLIDE_DIR_B : L.MI_SLIDE_DIR_B + 2] = slide_dir
    for leg in range(2):
        mf[leg] = r.aux[n, leg * L.NAUX_LEG + L.A_TOE_X]
    cmd = np.array([r.aux[n, L.A_TAU_CMD], r.aux[n, L.NAUX_LEG + L.A_TAU_CMD]])
    return mi, mf, cmd
