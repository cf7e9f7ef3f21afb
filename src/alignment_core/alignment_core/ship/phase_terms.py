"""The wave components' phase factors along the ship's track, in one compiled pass: for each
sample and component, from the phase phi, its rate phi' and minus its acceleration -phi'',
the real and imaginary parts of Z = e^{i phi}, i phi' Z and (i phi'' - phi'^2) Z that the
response's value, rate and acceleration are the products of (spectral.WaveFrequencyOnTrack).

numpy's form of the same arithmetic makes eight temporaries the size of the (samples x
components) block; one pass over it is about twice as fast (the kernel's cos and sin are the C
library's, as numpy's are here, and each product is the one numpy forms: the same bits)."""
from __future__ import annotations

import numpy as np

from alignment_core.compiled import kernel


@kernel
def phase_terms(ph, pd, pdd, cs, sn, spd, cpd, gr, gi):
    """Into cs, sn, spd, cpd, gr, gi (each (N, M), like ph): cos(ph), sin(ph), sin(ph) pd,
    cos(ph) pd, sin(ph) pdd - cos(ph) pd pd and -(cos(ph) pdd + sin(ph) pd pd), where ph
    (N, M) is the phase, pd (N, M) its rate and pdd (N, M) minus its acceleration."""
    n, m = ph.shape
    for i in range(n):
        for j in range(m):
            c = np.cos(ph[i, j])              # numpy's: NaN at an infinite phase, interpreted too
            s = np.sin(ph[i, j])
            d = pd[i, j]
            dd = pdd[i, j]
            sd = s * d
            cd = c * d
            cs[i, j] = c
            sn[i, j] = s
            spd[i, j] = sd
            cpd[i, j] = cd
            gr[i, j] = s * dd - cd * d
            gi[i, j] = -(c * dd + sd * d)

