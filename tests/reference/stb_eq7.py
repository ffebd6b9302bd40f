"""The seed's closed form for the STB heald mechanism, eq. (2)-(7) of Grigoriev et al.

Written from Grigoriev et al. (2002) without mechcirc, for any positive parameters.  Works
with numpy arrays of ω or, given ``j`` and a module ``mp`` of the same
interface, with mpmath numbers.
"""


def full_K(omega, p):
    """K(ω) by eq. (7); ``p`` maps m1..m12, k0, k4, k5, eta1..eta4 to values (eta4 = 1)."""
    m1, m2, m3, m4, m5 = (p[f"m{i}"] for i in range(1, 6))
    m6, m7, m8, m9, m10, m11, m12 = (p[f"m{i}"] for i in range(6, 13))
    k0, k4, k5 = p["k0"], p["k4"], p["k5"]
    eta1, eta2, eta3, eta4 = p["eta1"], p["eta2"], p["eta3"], p["eta4"]
    w = omega
    eta_c = eta1**2 * eta2 * eta3**2
    eta_B = eta1**2 * eta2
    eta_C = eta_c
    M_I = m10 * m11 * m12 / (m10 * m12 + m11 * m12 + m10 * m11)
    M_II = m6 * m7 * m8 * m9 / (m7 * m8 * m9 + m6 * m8 * m9 + m6 * m7 * m9 + m6 * m7 * m8)
    M_III = (m1 * m2 * m3 * m4 * eta1**2 * eta_B * eta_C
             / (m2 * m3 * m4 * eta1**2 * eta_B * eta_C + m1 * m3 * m4 * eta_B * eta_C
                + m1 * m2 * m4 * eta1**2 * eta_C + m1 * m2 * m3 * eta1**2 * eta_B))
    A = m5 * w**2 - k5
    B = M_I * M_II * w**2 - k0 * (M_I * eta4 + M_II)
    C = m5 * w**2 * (k4 * eta_c + k5) - k4 * k5 * eta_c
    num = w**2 * A * (M_III * B - M_I * M_II * k0 * eta4) - B * C
    den = w * M_III * (A * w**2 * M_I * M_II * k0 * eta4 + B * C)
    return 1j * num / den


def netlist(p, V0=0.1):
    """The same circuit as a netlist (Fig. 3), with numbers written out."""
    e = {k: repr(float(v)) for k, v in p.items()}
    eta1, eta2, eta3 = p["eta1"], p["eta2"], p["eta3"]
    eta_B = eta1**2 * eta2
    eta_C = eta1**2 * eta2 * eta3**2
    return f"""
drive V T 0 velocity={V0!r}
mass m1 T A {e['m1']}
mass m2 A B {e['m2']} eta={eta1**2!r}
mass m3 B C {e['m3']} eta={eta_B!r}
mass m4 C D {e['m4']} eta={eta_C!r}
spring k4 D 0 {e['k4']} eta={eta_C!r}
mass m5 D E {e['m5']}
spring k5 E 0 {e['k5']}
mass m6 D F {e['m6']}
mass m7 F G {e['m7']}
mass m8 G H {e['m8']}
mass m9 H I {e['m9']}
mass m10 I J {e['m10']}
mass m11 J L {e['m11']}
mass m12 L M {e['m12']}
spring k0 M 0 {e['k0']}
"""


def _parts(w, p):
    m = [None] + [p[f"m{i}"] for i in range(1, 13)]
    k0, k4, k5 = p["k0"], p["k4"], p["k5"]
    eta1, eta2, eta3, eta4 = p["eta1"], p["eta2"], p["eta3"], p["eta4"]
    eta_c = eta1**2 * eta2 * eta3**2
    eta_B = eta1**2 * eta2
    M_I = m[10] * m[11] * m[12] / (m[10] * m[12] + m[11] * m[12] + m[10] * m[11])
    M_II = m[6] * m[7] * m[8] * m[9] / (m[7] * m[8] * m[9] + m[6] * m[8] * m[9]
                                         + m[6] * m[7] * m[9] + m[6] * m[7] * m[8])
    M_III = (m[1] * m[2] * m[3] * m[4] * eta1**2 * eta_B * eta_c
             / (m[2] * m[3] * m[4] * eta1**2 * eta_B * eta_c + m[1] * m[3] * m[4] * eta_B * eta_c
                + m[1] * m[2] * m[4] * eta1**2 * eta_c + m[1] * m[2] * m[3] * eta1**2 * eta_B))
    A = m[5] * w**2 - k5
    B = M_I * M_II * w**2 - k0 * (M_I * eta4 + M_II)
    C = m[5] * w**2 * (k4 * eta_c + k5) - k4 * k5 * eta_c
    return M_I, M_II, M_III, A, B, C, k0, eta4


def numerator(w, p):
    """Eq. (7)'s numerator: ω² A (M_III B − M_I M_II k0 η4) − B C (zeros of K)."""
    M_I, M_II, M_III, A, B, C, k0, eta4 = _parts(w, p)
    return w**2 * A * (M_III * B - M_I * M_II * k0 * eta4) - B * C


def denominator(w, p):
    """Eq. (7)'s denominator: ω M_III (A ω² M_I M_II k0 η4 + B C) (poles of K)."""
    M_I, M_II, M_III, A, B, C, k0, eta4 = _parts(w, p)
    return w * M_III * (A * w**2 * M_I * M_II * k0 * eta4 + B * C)
