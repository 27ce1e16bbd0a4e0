"""Wall materials: complex permittivity and Fresnel reflection coefficients.

Concrete at 900 MHz: ITU-R P.2040-1 Table 3 gives eta' = 5.31 and
sigma = 0.0326 f^0.8095 S/m (f in GHz), i.e. epsilon = eta' - j 17.98 sigma / f
= 5.31 - j0.60 at 0.9 GHz (eq. 9b), the project's value (docs/model/tunnel.md §2.1); the tests pin its
8.0 dB loss at normal incidence.

Conventions (time factor exp(+j omega t), so a lossy medium has Im(epsilon) < 0):
TE ("s", E perpendicular to the plane of incidence) and TM ("p", E in the plane) with
the p unit vector taken as s x k for the incident and the reflected wave alike, which
makes Gamma_TM -> -1 at grazing incidence and Gamma_TM = -Gamma_TE at normal incidence.
"""

from __future__ import annotations

import numpy as np

CONCRETE_900MHZ = complex(5.31, -0.60)
"""Relative permittivity of the concrete lining at 900 MHz [ITU-R P.2040-1].

Dimensionless, eps' - j eps'' with the exp(+j omega t) convention of this module (Im < 0 for a lossy wall)."""


def _check_eps(eps: complex) -> complex:
    eps = complex(eps)
    if not eps.real > 1.0 or eps.imag > 0.0:
        raise ValueError(f"eps must have real part > 1 and imaginary part <= 0 (exp(+jwt)), got {eps!r}")
    return eps


def _root(eps: complex, cos_i: np.ndarray) -> np.ndarray:
    sin2 = 1.0 - cos_i**2
    return np.sqrt(eps - sin2 + 0j)


def _check_cos(cos_i) -> np.ndarray:
    c = np.asarray(cos_i, dtype=float)
    if np.any(c < 0.0) or np.any(c > 1.0):
        raise ValueError("cos_i (cosine of the incidence angle from the normal) must be in [0, 1]")
    return c


def fresnel_te(cos_i, eps: complex = CONCRETE_900MHZ) -> np.ndarray:
    """TE (s, perpendicular) reflection coefficient for incidence cosine ``cos_i``.

    Gamma_TE = (cos t - sqrt(eps - sin^2 t)) / (cos t + sqrt(eps - sin^2 t))
    (ITU-R P.2040-1 eq. 31a with mu = 1).

    Parameters
    ----------
    cos_i : float or array_like
        Cosine of the incidence angle from the wall normal [1]; in [0, 1].
    eps : complex
        Relative permittivity of the wall [1]; real part > 1, imaginary part <= 0
        (exp(+j omega t)).

    Returns
    -------
    numpy.ndarray
        Complex reflection coefficient Gamma_TE [1], the shape of ``cos_i``.

    Raises
    ------
    ValueError
        When ``eps`` is not a lossy permittivity as above or ``cos_i`` lies outside [0, 1].
    """
    eps = _check_eps(eps)
    c = _check_cos(cos_i)
    r = _root(eps, c)
    return (c - r) / (c + r)


def fresnel_tm(cos_i, eps: complex = CONCRETE_900MHZ) -> np.ndarray:
    """TM (p, parallel) reflection coefficient for incidence cosine ``cos_i``.

    Gamma_TM = (eps cos t - sqrt(eps - sin^2 t)) / (eps cos t + sqrt(eps - sin^2 t))
    (ITU-R P.2040-1 eq. 31b with mu = 1, p vector = s x k on both sides).

    Parameters
    ----------
    cos_i : float or array_like
        Cosine of the incidence angle from the wall normal [1]; in [0, 1].
    eps : complex
        Relative permittivity of the wall [1]; real part > 1, imaginary part <= 0
        (exp(+j omega t)).

    Returns
    -------
    numpy.ndarray
        Complex reflection coefficient Gamma_TM [1], the shape of ``cos_i``.

    Raises
    ------
    ValueError
        When ``eps`` is not a lossy permittivity as above or ``cos_i`` lies outside [0, 1].
    """
    eps = _check_eps(eps)
    c = _check_cos(cos_i)
    r = _root(eps, c)
    return (eps * c - r) / (eps * c + r)


def reflection_loss_db(gamma) -> np.ndarray:
    """Reflection loss -20 log10 |Gamma| [dB].

    Parameters
    ----------
    gamma : complex or array_like
        Reflection coefficient Gamma [1].

    Returns
    -------
    numpy.ndarray
        Reflection loss [dB], the shape of ``gamma``.
    """
    return -20.0 * np.log10(np.abs(gamma))


def eh11_attenuation_db_per_m(
    wavelength_m: float, width_m: float, height_m: float, eps: complex = CONCRETE_900MHZ
) -> float:
    """Attenuation of the dominant vertically polarized mode EH11 of a rectangular tunnel
    (Emslie, Lagace & Strong 1975, eq. 7 with the polarizations swapped) [dB/m]:

        alpha = 4.343 lambda^2 Re[ 1 / (w^3 sqrt(eps - 1)) + eps / (h^3 sqrt(eps - 1)) ]

    (side walls TE, floor and ceiling TM for a vertical field).

    Parameters
    ----------
    wavelength_m : float
        Free-space wavelength lambda [m]; positive.
    width_m : float
        Width w of the tunnel, between the side walls [m]; positive.
    height_m : float
        Height h of the tunnel, floor to ceiling [m]; positive.
    eps : complex
        Relative permittivity of the walls [1] (imaginary part <= 0, exp(+j omega t)).

    Returns
    -------
    float
        Attenuation of the EH11 mode [dB/m].

    Raises
    ------
    ValueError
        When ``wavelength_m``, ``width_m`` or ``height_m`` is not positive.
    """
    if wavelength_m <= 0 or width_m <= 0 or height_m <= 0:
        raise ValueError("wavelength_m, width_m and height_m must be positive")
    root = np.sqrt(complex(eps) - 1.0)
    return float(4.343 * wavelength_m**2 * np.real(1.0 / (width_m**3 * root) + eps / (height_m**3 * root)))


CIRCULAR_MODES = {
    "EH11": (2.404825557695773, "hybrid"),
    "TE01": (3.831705970207512, "te"),
    "TM01": (3.831705970207512, "tm"),
}
"""u_nm (the m-th zero of J_{n-1}) and the mode family of the lowest circular-guide modes."""


def circular_attenuation_db_per_m(
    wavelength_m: float, radius_m: float, mode: str = "EH11", eps: complex = CONCRETE_900MHZ
) -> float:
    """Attenuation of a mode of a hollow circular guide in a lossy dielectric (Marcatili &
    Schmeltzer 1964, eq. 35): alpha = (u_nm / 2 pi)^2 lambda^2 / a^3 Re(nu_n) [Np/m] with
    nu = 1/sqrt(eps - 1) (TE0m), eps/sqrt(eps - 1) (TM0m), (eps + 1)/(2 sqrt(eps - 1))
    (hybrid EH_nm) [dB/m].

    Parameters
    ----------
    wavelength_m : float
        Free-space wavelength lambda [m]; positive.
    radius_m : float
        Radius a of the guide [m]; positive.
    mode : {'EH11', 'TE01', 'TM01'}
        The mode (:data:`CIRCULAR_MODES`).
    eps : complex
        Relative permittivity of the wall [1] (imaginary part <= 0, exp(+j omega t)).

    Returns
    -------
    float
        Attenuation of the mode [dB/m].

    Raises
    ------
    ValueError
        When ``wavelength_m`` or ``radius_m`` is not positive or ``mode`` is unknown.
    """
    if wavelength_m <= 0 or radius_m <= 0:
        raise ValueError("wavelength_m and radius_m must be positive")
    if mode not in CIRCULAR_MODES:
        raise ValueError(f"mode must be one of {tuple(CIRCULAR_MODES)}, got {mode!r}")
    u, kind = CIRCULAR_MODES[mode]
    eps = complex(eps)
    root = np.sqrt(eps - 1.0)
    nu = {"te": 1.0 / root, "tm": eps / root, "hybrid": (eps + 1.0) / (2.0 * root)}[kind]
    return float(20.0 * np.log10(np.e) * (u / (2.0 * np.pi)) ** 2 * wavelength_m**2 / radius_m**3 * np.real(nu))
