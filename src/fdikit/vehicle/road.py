"""Road and wind inputs of the nonlinear PATH vehicle: spatial road profiles and a time-domain crosswind.

The car samples the road **in distance, not time**: each wheel's height ξ is interpolated at the distance that
wheel has travelled (front wheels at ``s``, rear wheels at ``s - wheelbase``), so a change of speed and the
front-to-rear delay of Douglas et al. 1996, §8.2.10, (8.109) come out right without a speed in the road model.
Every generator returns a :class:`RoadProfile` (left and right heights on the grid ``s_k = k · spacing``):
:func:`flat_road`; :func:`robson_road` (§2.1.2, Robson 1980, one track used left and right) with
:func:`robson_psd`; :func:`gill_road` (§8.2.10, Gill 1983, correlated tracks) with :func:`gill_psd` and
:func:`gill_coherence`; :func:`sine_bump` (§8.3.1).  :func:`crosswind_pulse` is the §8.3.2 wind, in time.

Random profiles are exact: a first-order filter ``dx/ds = -a x + g w`` driven by white noise in distance is an
Ornstein–Uhlenbeck process whose grid samples are the AR(1) sequence ``x[k+1] = φ x[k] + e[k]``, ``φ = exp(-a·ds)``,
innovation variance ``σ_x²(1 - φ²)``, ``σ_x² = g²/(2a)``, started from the stationary ``N(0, σ_x²)``.  White noise
"of unit PSD" has unit intensity, ``E[w(s) w(s')] = δ(s - s')``.  Spectra are one-sided, in m²/(cycle/m), as
:func:`scipy.signal.welch` returns them for a profile sampled at ``fs = 1/spacing``.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import ParameterError

__all__ = ["RoadProfile", "flat_road", "robson_road", "robson_psd", "gill_road", "gill_psd", "gill_coherence",
           "sine_bump", "crosswind_pulse"]

# ---------------------------------------------------------------------------------------------- helpers
def _rng(rng) -> np.random.Generator:
    if rng is None or isinstance(rng, np.random.Generator):
        return np.random.default_rng(rng)  # the generator itself, or fresh entropy
    if isinstance(rng, bool | np.bool_) or not isinstance(rng, numbers.Integral) or rng < 0:
        raise ParameterError(f"rng must be a seed (an int >= 0), a numpy.random.Generator or None, got {rng!r:.60}")
    return np.random.default_rng(int(rng))


def _grid(length, spacing) -> tuple[float, int]:
    """The checked spacing and the number of grid points covering ``[0, length]``."""
    length = validate.positive("length", length)
    spacing = validate.positive("spacing", spacing)
    if spacing > length:
        raise ParameterError(f"spacing ({spacing} m) must not exceed length ({length} m); use a finer grid")
    return spacing, int(np.ceil(length / spacing - 1e-9)) + 1


def _ar1(rng: np.random.Generator, n: int, phi: float, var: float) -> np.ndarray:
    """A stationary AR(1) sequence of ``n`` samples, coefficient ``phi``, variance ``var`` (exact OU samples)."""
    import scipy.signal

    e = rng.standard_normal(n)
    e[0] *= np.sqrt(var)
    e[1:] *= np.sqrt(var * (1.0 - phi * phi))
    return scipy.signal.lfilter([1.0], [1.0, -phi], e)


def _wavenumbers(wavenumber, spacing) -> tuple[np.ndarray, float | None]:
    lam = validate.as_array("wavenumber", wavenumber)
    if np.any(lam < 0):
        raise ParameterError("wavenumber must be >= 0 (one-sided spectra, cycles/m); drop the negative entries")
    spacing = None if spacing is None else validate.positive("spacing", spacing)
    if spacing is not None and np.any(lam > 0.5 / spacing * (1 + 1e-12)):
        raise ParameterError(f"wavenumber must not exceed the grid's Nyquist wavenumber 1/(2·spacing) = "
                             f"{0.5 / spacing:g} cycles/m; drop the larger entries or pass spacing=None")
    return lam, spacing


def _ou_psd(lam: np.ndarray, gain2: float, a: float, spacing: float | None) -> np.ndarray:
    """One-sided PSD [per cycle/m] of ``dx/ds = -a x + g w`` (``gain2 = g²``), continuous or sampled at ``spacing``."""
    if spacing is None:
        return 2.0 * gain2 / ((2.0 * np.pi * lam) ** 2 + a * a)
    phi = np.exp(-a * spacing)
    q = gain2 / (2.0 * a) * (1.0 - phi * phi)
    return 2.0 * spacing * q / (1.0 - 2.0 * phi * np.cos(2.0 * np.pi * lam * spacing) + phi * phi)


# ---------------------------------------------------------------------------------------------- the profile
@dataclass(frozen=True, eq=False)
class RoadProfile:
    """Left and right road heights on the grid ``s_k = k · spacing`` of travelled distance.

    Parameters
    ----------
    spacing : float
        Grid step ``ds`` [m], > 0.
    left, right : array_like
        Heights [m] of the left and right wheel tracks at ``s_k``: 1-D, finite, the same length (>= 2).
    label : str, default ''
        What the profile is (a sum joins the labels with " + ").

    Raises
    ------
    ParameterError
        For a non-positive spacing, tracks not 1-D, non-finite, of unequal length or under 2 points, a non-str label.

    References
    ----------
    Douglas et al. 1996, §8.1.3, (8.16): ξ_i, the road under wheel i; §8.2.10, (8.109): rear sees front's road.

    Examples
    --------
    >>> from fdikit.vehicle.road import RoadProfile
    >>> road = RoadProfile(spacing=1.0, left=[0.0, 0.02, 0.0], right=[0.0, 0.0, 0.0], label="step")
    >>> road.length, road.heights(0.5)
    (2.0, (0.01, 0.0))
    """

    spacing: float
    left: np.ndarray
    right: np.ndarray
    label: str = ""

    def __post_init__(self):
        spacing = validate.positive("spacing", self.spacing)
        left = validate.as_array("left", self.left)
        right = validate.as_array("right", self.right)
        for name, track in (("left", left), ("right", right)):
            if track.ndim != 1 or track.size < 2:
                raise ParameterError(f"{name} must be a 1-D array of at least 2 heights, got shape {track.shape}")
            track.setflags(write=False)
        if left.size != right.size:
            raise ParameterError(f"left and right must have the same length, got {left.size} and {right.size}; "
                                 "sample both tracks on the same grid")
        if not isinstance(self.label, str):
            raise ParameterError(f"label must be a string, got {type(self.label).__name__}")
        object.__setattr__(self, "spacing", spacing)
        object.__setattr__(self, "left", left)
        object.__setattr__(self, "right", right)

    @property
    def length(self) -> float:
        """Distance [m] covered by the grid, ``(n - 1) · spacing``."""
        return (self.left.size - 1) * self.spacing

    def heights(self, distance) -> tuple:
        """Left and right heights [m] at travelled ``distance`` [m], linearly interpolated on the grid.

        Parameters
        ----------
        distance : float or array_like
            Distances in ``[0, length]``.

        Returns
        -------
        left, right : float or ndarray
            Floats for a scalar ``distance``, else arrays of its shape.

        Raises
        ------
        ParameterError
            For a non-finite distance or one outside ``[0, length]`` (generate a longer road; start a wheelbase in).

        Examples
        --------
        >>> from fdikit.vehicle.road import RoadProfile
        >>> RoadProfile(0.5, [0.0, 1.0, 3.0], [0.0, 0.0, 0.0]).heights([0.25, 0.75])[0].tolist()
        [0.5, 2.0]
        """
        s, slack = validate.as_array("distance", distance), 1e-9 * self.spacing
        if s.size and s.max() > self.length + slack:
            raise ParameterError(f"distance {s.max():g} m lies beyond the end of the road profile ({self.length:g} m "
                                 f"{self.label}); generate a longer road")
        if s.size and s.min() < -slack:
            raise ParameterError(f"distance {s.min():g} m is negative; the profile starts at s = 0 (start the car "
                                 "a wheelbase in, so that the rear wheels' s - wheelbase is >= 0)")
        x = np.clip(s, 0.0, self.length) / self.spacing
        k = np.minimum(np.floor(x).astype(np.intp), self.left.size - 2)
        f = x - k
        left = self.left[k] * (1.0 - f) + self.left[k + 1] * f
        right = self.right[k] * (1.0 - f) + self.right[k + 1] * f
        if s.ndim == 0:
            return float(left), float(right)
        return left, right

    def __add__(self, other: RoadProfile) -> RoadProfile:
        """The sum of two profiles on the same grid (e.g. a random road plus a bump)."""
        if not isinstance(other, RoadProfile):
            raise ParameterError(f"a RoadProfile can only be added to a RoadProfile, got {type(other).__name__}")
        if not np.isclose(self.spacing, other.spacing, rtol=1e-12, atol=0.0) or self.left.size != other.left.size:
            raise ParameterError(f"profiles on different grids cannot be added ({self.left.size} points at "
                                 f"{self.spacing:g} m, {other.left.size} at {other.spacing:g} m); use the same "
                                 "length and spacing")
        label = " + ".join(x for x in (self.label, other.label) if x)
        return RoadProfile(self.spacing, self.left + other.left, self.right + other.right, label)

    def __repr__(self) -> str:
        return f"RoadProfile({self.label!r}, length={self.length:g} m, spacing={self.spacing:g} m)"


# ---------------------------------------------------------------------------------------------- generators
def flat_road(length: float, spacing: float = 0.05) -> RoadProfile:
    """A flat road: zero heights on both tracks over ``[0, length]``.

    Parameters
    ----------
    length : float
        Distance to cover [m], > 0 (the grid is extended to the next multiple of ``spacing``).
    spacing : float, default 0.05
        Grid step [m].

    Returns
    -------
    RoadProfile

    Raises
    ------
    ParameterError
        For a non-positive length or spacing, or a spacing longer than the road.

    References
    ----------
    Douglas et al. 1996, §8.1.3, (8.16) with ξ_i = 0.

    Examples
    --------
    >>> from fdikit.vehicle.road import flat_road
    >>> flat_road(10.0).heights(3.3)
    (0.0, 0.0)
    """
    spacing, n = _grid(length, spacing)
    return RoadProfile(spacing, np.zeros(n), np.zeros(n), "flat")


def _robson_params(roughness, cutoff, psd_convention) -> tuple[float, float]:
    """``(g², a)`` of ``dr/ds = -a r + g w_s`` for the Robson road."""
    roughness, cutoff = validate.positive("roughness", roughness), validate.positive("cutoff", cutoff)
    validate.choice("psd_convention", psd_convention, ("report", "one-sided"))
    gain2 = 2.0 * np.pi * roughness if psd_convention == "report" else 2.0 * np.pi ** 2 * roughness
    return gain2, 2.0 * np.pi * cutoff


def robson_road(length: float, *, roughness: float = 1e-7, cutoff: float = 0.01, spacing: float = 0.05,
                psd_convention: str = "report", rng: np.random.Generator | int | None = None) -> RoadProfile:
    """Random road of the PATH report's §2.1.2 (Robson 1980): one first-order track, the same left and right.

    The report approximates the PSD (2.5) by the rational (2.6), ``P(λ) = R_c / (λ² + λ_0²)`` with λ in cycles/m,
    and integrates ``ṙ = -ω_0 r + √(2π V R_c) w``, ``ω_0 = 2π V λ_0``.  Divided by the speed ``V`` (``ds = V dt``;
    ``w(t) = √V w_s(V t)`` has unit intensity when ``w_s`` has), this is the speed-free ``dr/ds = -2π λ_0 r + g w_s``
    with ``g = √(2π R_c)``.  Its one-sided PSD is ``G(λ) = 2 g² / ((2πλ)² + (2πλ_0)²) = g² / (2π² (λ² + λ_0²))``,
    its variance ``g² / (4π λ_0)``; the two choices of ``psd_convention`` give

    * ``"report"`` (default): ``g² = 2π R_c``, ``G(λ) = R_c / (π (λ² + λ_0²))``, ``σ_r² = R_c / (2 λ_0)`` (5e-6 m²);
    * ``"one-sided"``: ``g² = 2π² R_c`` (√π times the text's gain), ``G(λ)`` is (2.6) itself read as a one-sided
      PSD in m²/(cycle/m), ``σ_r² = π R_c / (2 λ_0)`` (σ_r ≈ 4.0 mm against 2.2 mm for the freeway values).

    The text's form is the default: it is the disturbance the report's 32-state model integrates, and the report
    does not say whether (2.6) is one- or two-sided or per radian (the readings differ by π in power).  The
    profile is exact (module docstring): AR(1) on the grid, ``φ = exp(-2π λ_0 ds)``, stationary start.

    Parameters
    ----------
    length : float
        Distance to cover [m], > 0.
    roughness, cutoff : float, default 1e-7 and 0.01
        ``R_c`` [m²·(cycle/m)] and ``λ_0`` [cycles/m], > 0 (the defaults: a typical freeway, §2.1.2).
    spacing : float, default 0.05
        Grid step [m].
    psd_convention : {'report', 'one-sided'}, default 'report'
        The gain of the shaping filter (above).
    rng : numpy.random.Generator or int seed (>= 0), optional
        Source of the white noise (None: fresh entropy, not reproducible).

    Returns
    -------
    RoadProfile
        Identical ``left`` and ``right``.

    Raises
    ------
    ParameterError
        For a non-positive length, spacing, roughness or cutoff, an unknown convention or a bad ``rng``.

    References
    ----------
    Douglas et al. 1996, §2.1.2, (2.5), (2.6) and the shaping filter below (2.6); Robson 1980.

    Examples
    --------
    >>> from fdikit.vehicle.road import robson_road
    >>> road = robson_road(1000.0, rng=1)
    >>> road.left.size, bool((road.left == road.right).all())
    (20001, True)
    """
    gain2, a = _robson_params(roughness, cutoff, psd_convention)
    spacing, n = _grid(length, spacing)
    gen = _rng(rng)
    track = _ar1(gen, n, float(np.exp(-a * spacing)), gain2 / (2.0 * a))
    return RoadProfile(spacing, track, track.copy(), f"Robson road (R_c={roughness:g}, {psd_convention})")


def robson_psd(wavenumber, roughness: float = 1e-7, cutoff: float = 0.01, psd_convention: str = "report", *,
               spacing: float | None = None) -> np.ndarray:
    """The one-sided spatial PSD [m²/(cycle/m)] that :func:`robson_road` produces.

    ``G(λ) = R_c / (π (λ² + λ_0²))`` for ``"report"``, ``R_c / (λ² + λ_0²)`` for ``"one-sided"`` (derivation in
    :func:`robson_road`).  With ``spacing``, the exact PSD of the sampled AR(1) sequence (the continuous one
    folded about ``1/(2 ds)``): ``G_d(λ) = 2 ds q / (1 - 2 φ cos(2π λ ds) + φ²)``, ``q = σ_r² (1 - φ²)``, for
    ``0 < λ <= 1/(2 ds)``.

    Parameters
    ----------
    wavenumber : array_like
        Wavenumbers λ [cycles/m], >= 0 (<= ``1/(2·spacing)`` when ``spacing`` is given).
    roughness, cutoff, psd_convention
        As for :func:`robson_road`.
    spacing : float, optional
        Grid step [m] of the sampled profile; None: the continuous process.

    Returns
    -------
    ndarray
        The PSD at each wavenumber.

    Raises
    ------
    ParameterError
        For negative (or above-Nyquist) wavenumbers or bad parameters.

    References
    ----------
    Douglas et al. 1996, §2.1.2, (2.6); Robson 1980.

    Examples
    --------
    >>> from fdikit.vehicle.road import robson_psd
    >>> round(float(robson_psd(0.0, psd_convention="one-sided")), 12)  # R_c / λ_0²
    0.001
    """
    gain2, a = _robson_params(roughness, cutoff, psd_convention)
    lam, spacing = _wavenumbers(wavenumber, spacing)
    return _ou_psd(lam, gain2, a, spacing)


def _gill_params(intensity, coherence, gamma) -> tuple[float, float, float, float]:
    """``(c1, c2, γ1, γ2)``: the high-wavenumber levels and the filter coefficients [1/m] of ξ_M and s·θ_M."""
    intensity = validate.positive("intensity", intensity)
    rho = validate.in_range("coherence", coherence, 0.0, 1.0)
    if gamma is None:
        g1 = 2.0 * np.pi * 0.01
        g2 = g1 * np.sqrt((1.0 + rho) / (1.0 - rho)) if rho < 1.0 else g1
    else:
        if isinstance(gamma, str) or np.ndim(gamma) != 1 or len(gamma) != 2:
            raise ParameterError(f"gamma must be a pair (γ1, γ2) of filter coefficients [1/m], got {gamma!r:.60}")
        g1, g2 = validate.positive("gamma[0]", gamma[0]), validate.positive("gamma[1]", gamma[1])
    k = (g2 / g1) ** 2 * (1.0 - rho) / (1.0 + rho)  # c2 / c1, from the coherency rho at zero wavenumber
    return intensity / (1.0 + k), intensity * k / (1.0 + k), g1, g2


def gill_road(length: float, *, intensity: float, coherence: float = 0.75, track: float = 1.52,
              spacing: float = 0.05, gamma: tuple[float, float] | None = None,
              rng: np.random.Generator | int | None = None) -> RoadProfile:
    """Correlated two-track random road of the PATH report's §8.2.10 (Gill 1983).

    (8.106): ``η_left = ξ_M + s_l θ_M``, ``η_right = ξ_M + s_r θ_M``, a mean track ξ_M and a cross slope θ_M [rad]
    that are independent first-order processes, here in distance (speed drops out): ``dξ_M/ds = -γ_1 ξ_M + σ_1 w_1``,
    ``dθ_M/ds = -γ_2 θ_M + σ_2 w_2`` (``w_i`` independent unit-intensity white noise).  The signed half-tracks follow
    ISO 8855 (y to the LEFT): ``s_l = +track/2``, ``s_r = -track/2``.  With ``b = track/2``, ``c_1 = σ_1²/(2π²)``,
    ``c_2 = b² σ_2²/(2π²)`` and ``λ_i = γ_i/(2π)`` the one-sided spectra [per cycle/m] of each track and of the pair
    are ``G(λ) = c_1/(λ² + λ_1²) + c_2/(λ² + λ_2²)`` and ``G_lr(λ) = c_1/(λ² + λ_1²) - c_2/(λ² + λ_2²)`` (real), the
    coherency ``ρ(λ) = G_lr/G``.  fdikit chooses the σ's from two conditions:

    * ``ρ(0) = coherence`` (the correlation coefficient of the long-wavelength components, 0.75 in §8.3.2):
      ``c_2/c_1 = k = (γ_2/γ_1)² (1 - ρ_0)/(1 + ρ_0)``;
    * ``G(λ) → intensity/λ²`` at wavenumbers above both cut-offs: ``c_1 + c_2 = S_0``,

    so ``c_1 = S_0/(1 + k)``, ``c_2 = S_0 k/(1 + k)``, ``σ_1 = π √(2 c_1)``, ``σ_2 = π √(2 c_2)/b``.  Default
    ``gamma`` (fdikit's choice): ``γ_1 = 2π·0.01`` 1/m (Robson's freeway cut-off λ_0 = 0.01 cycles/m for ξ_M) and
    ``γ_2 = γ_1 √((1 + ρ_0)/(1 - ρ_0))`` (2.65 γ_1 for 0.75), making ``k = 1``: ``ρ(λ) = (λ_2² - λ_1²)/(2λ² + λ_1² +
    λ_2²)`` falls from 0.75 to 0.10 at 0.05 cycles/m and to 0 at short wavelengths ("high at low wavenumber and falls
    fast", §8.3.2).  Since ``ρ(∞) = (1 - k)/(1 + k)``, a larger γ_2/γ_1 anti-correlates the short waves.

    Changed from the printed equations: (8.107) multiplies state and noise by ``v_x`` and shows ``+γ``; the stable
    filter has ``-γ`` and, for unit-intensity white noise in time, the noise gain scales with ``√v_x`` (as for the
    Robson road), so the model is written in distance instead.  (8.108b) ``σ_2 = σ_1 s_2 √α`` is not dimensionally
    consistent (θ_M is an angle: σ_2 needs a 1/length); a consistent reading, ``σ_2 = (σ_1/s_2) √((1 - α)/(1 + α))``
    with (8.108a), makes the coherency α at HIGH wavenumber, so with the report's 0.75 short waves would stay
    correlated, against §8.3.2.  The two conditions above replace (8.108); ``coherence`` keeps α's meaning (0
    uncorrelated, 1 fully correlated, where θ_M = 0).

    Parameters
    ----------
    intensity : float
        ``S_0`` [m²·(cycle/m)], > 0: each track's one-sided PSD is ``S_0/λ²`` at high wavenumber (``S_0 = R_c``
        gives the level of :func:`robson_road` with ``psd_convention='one-sided'``).
    coherence : float in [0, 1], default 0.75
        ``ρ_0``, the left–right coherency at zero wavenumber.
    track : float, default 1.52
        Track width [m], > 0 (the half-tracks are ±track/2).  It scales θ_M only; the heights do not depend on it.
    gamma : (float, float), optional
        Filter coefficients ``(γ_1, γ_2)`` [1/m] of ξ_M and θ_M (cut-offs ``γ_i/(2π)`` cycles/m); default above.
    length, spacing, rng
        As for :func:`robson_road`.

    Returns
    -------
    RoadProfile

    Raises
    ------
    ParameterError
        For a non-positive length, spacing, intensity, track or γ, a coherence outside [0, 1], or a bad ``rng``.

    References
    ----------
    Douglas et al. 1996, §8.2.10, (8.106)–(8.109), and §8.3.2, Figs 8.27–8.28; Gill 1983.

    Examples
    --------
    >>> from fdikit.vehicle.road import gill_road
    >>> road = gill_road(500.0, intensity=1e-7, rng=3)
    >>> road.left.shape == road.right.shape, bool((road.left != road.right).any())
    (True, True)
    """
    c1, c2, g1, g2 = _gill_params(intensity, coherence, gamma)
    b = validate.positive("track", track) / 2.0
    spacing, n = _grid(length, spacing)
    gen = _rng(rng)
    s1, s2 = np.pi * np.sqrt(2.0 * c1), np.pi * np.sqrt(2.0 * c2) / b
    xi = _ar1(gen, n, float(np.exp(-g1 * spacing)), s1 * s1 / (2.0 * g1))
    theta = _ar1(gen, n, float(np.exp(-g2 * spacing)), s2 * s2 / (2.0 * g2))
    return RoadProfile(spacing, xi + b * theta, xi - b * theta, f"Gill road (S_0={intensity:g}, ρ_0={coherence:g})")


def gill_psd(wavenumber, *, intensity: float, coherence: float = 0.75, gamma: tuple[float, float] | None = None,
             spacing: float | None = None) -> np.ndarray:
    """One-sided PSD [m²/(cycle/m)] of each track of :func:`gill_road`.

    ``G(λ) = c_1/(λ² + λ_1²) + c_2/(λ² + λ_2²)`` (constants in :func:`gill_road`); with ``spacing``, sampled.

    Parameters
    ----------
    wavenumber, spacing
        As for :func:`robson_psd`.
    intensity, coherence, gamma
        As for :func:`gill_road`.

    Returns
    -------
    ndarray

    Raises
    ------
    ParameterError
        For negative (or above-Nyquist) wavenumbers or bad parameters.

    References
    ----------
    Douglas et al. 1996, §8.2.10, (8.106)–(8.107); Gill 1983.

    Examples
    --------
    >>> from fdikit.vehicle.road import gill_psd
    >>> round(float(gill_psd(100.0, intensity=1e-7)) * 100.0 ** 2, 12)  # → S_0 at high wavenumber
    1e-07
    """
    c1, c2, g1, g2 = _gill_params(intensity, coherence, gamma)
    lam, spacing = _wavenumbers(wavenumber, spacing)
    return _ou_psd(lam, 2 * np.pi ** 2 * c1, g1, spacing) + _ou_psd(lam, 2 * np.pi ** 2 * c2, g2, spacing)


def gill_coherence(wavenumber, *, coherence: float = 0.75, gamma: tuple[float, float] | None = None,
                   spacing: float | None = None, squared: bool = False) -> np.ndarray:
    """Left–right coherency ``ρ(λ) = G_lr/G`` of :func:`gill_road` (or its square, ``squared=True``).

    Real (the cross-spectrum is); ``coherence`` at λ = 0, with the default ``gamma`` ``(λ_2² - λ_1²)/(2λ² + λ_1² +
    λ_2²)``.  ``ρ²`` is what :func:`scipy.signal.coherence` estimates.  Intensity and track width do not enter.

    Parameters
    ----------
    wavenumber, spacing
        As for :func:`robson_psd`.
    coherence, gamma
        As for :func:`gill_road`.
    squared : bool, default False
        Return ``ρ²`` (the magnitude-squared coherence) instead of ``ρ``.

    Returns
    -------
    ndarray

    Raises
    ------
    ParameterError
        For negative (or above-Nyquist) wavenumbers or bad parameters.

    References
    ----------
    Douglas et al. 1996, §8.2.10, (8.106)–(8.108), and §8.3.2, Fig. 8.28; Gill 1983.

    Examples
    --------
    >>> from fdikit.vehicle.road import gill_coherence
    >>> [round(float(r), 3) for r in gill_coherence([0.0, 0.01, 0.05])]
    [0.75, 0.6, 0.103]
    """
    c1, c2, g1, g2 = _gill_params(1.0, coherence, gamma)
    if not isinstance(squared, bool | np.bool_):
        raise ParameterError(f"squared must be True or False, got {squared!r:.40}")
    lam, spacing = _wavenumbers(wavenumber, spacing)
    p1, p2 = _ou_psd(lam, 2 * np.pi ** 2 * c1, g1, spacing), _ou_psd(lam, 2 * np.pi ** 2 * c2, g2, spacing)
    rho = (p1 - p2) / (p1 + p2)
    return rho * rho if squared else rho


def sine_bump(length: float, *, position: float, height: float = 0.01, width: float = 0.3,
              spacing: float = 0.05) -> RoadProfile:
    """The (1 − cos) bump of §8.3.1 on both tracks: ``ξ(s) = (h/2)(1 - cos(2π (s - position)/width))``.

    One full period over ``[position, position + width]`` (peak ``h`` in the middle), zero elsewhere; exact values
    at the grid points, linear in between (:meth:`RoadProfile.heights`), so ``width/spacing`` intervals resolve it.

    Parameters
    ----------
    length : float
        Distance to cover [m], > 0 (that of the profile you add the bump to).
    position : float
        Start of the bump [m], >= 0, with ``position + width <= length``.
    height, width : float, default 0.01 and 0.3
        Peak height [m] (negative: a dip) and length along the road [m] (> 0), as in §8.3.1.
    spacing : float, default 0.05
        Grid step [m].

    Returns
    -------
    RoadProfile

    Raises
    ------
    ParameterError
        For a non-positive length, spacing or width, a negative position, a bump off the road, a non-finite height.

    References
    ----------
    Douglas et al. 1996, §8.3.1, Fig. 8.16 (0.01 m high, 0.3 m wide bump at 27 m/s).

    Examples
    --------
    >>> from fdikit.vehicle.road import sine_bump
    >>> bump = sine_bump(10.0, position=2.0)
    >>> round(bump.heights(2.15)[0], 12), bump.heights(1.9)
    (0.01, (0.0, 0.0))
    """
    spacing, n = _grid(length, spacing)
    position, width, height = (validate.non_negative("position", position), validate.positive("width", width),
                               validate.number("height", height))
    if position + width > (n - 1) * spacing + 1e-9 * spacing:
        raise ParameterError(f"the bump (position {position:g} m + width {width:g} m) does not fit on a road of "
                             f"length {length:g} m; use a longer length or an earlier position")
    u = (np.arange(n) * spacing - position) / width
    xi = np.where((u > 0) & (u < 1), 0.5 * height * (1.0 - np.cos(2.0 * np.pi * u)), 0.0)
    return RoadProfile(spacing, xi, xi.copy(), f"bump ({height:g} m x {width:g} m at {position:g} m)")


def crosswind_pulse(t, *, speed: float = 15.0, start: float = 1.0, duration: float = 10.0,
                    direction: float = np.pi / 2) -> np.ndarray:
    """Earth-frame wind velocity of a rectangular crosswind pulse (§8.3.2: 15 m/s for 10 s) at times ``t``.

    ``W(t) = speed · (cos direction, sin direction)`` for ``start <= t < start + duration``, 0 otherwise.  Signs
    follow ISO 8855: earth X forward (the car's initial heading), Y to the LEFT, Z up; ``direction`` is the angle
    of the air's velocity from +X toward +Y, so the default π/2 gives ``W_Y = +speed``, a wind blowing toward the
    left (from the car's right).  The relative wind is ``(W_X - v_X, W_Y - v_Y)`` (§8.2.4, (8.83)–(8.84)).  The
    start (1 s) is fdikit's choice; the report gives the speed and the duration only.

    Parameters
    ----------
    t : float or array_like
        Times [s], finite.
    speed : float, default 15.0
        Wind speed [m/s] during the pulse, >= 0.
    start, duration : float, default 1.0 and 10.0
        Onset time [s] and pulse length [s] (> 0).
    direction : float, default π/2
        Direction [rad] of the wind velocity, counter-clockwise from earth +X.

    Returns
    -------
    (N, 2) ndarray
        ``(W_X, W_Y)`` [m/s] at each of the N times (N = 1 for a scalar ``t``).

    Raises
    ------
    ParameterError
        For non-finite times, a negative speed, a non-positive duration, a non-finite start or direction.

    References
    ----------
    Douglas et al. 1996, §8.2.4, (8.82)–(8.84), and §8.3.2, Fig. 8.26.

    Examples
    --------
    >>> from fdikit.vehicle.road import crosswind_pulse
    >>> crosswind_pulse([0.0, 5.0, 11.0]).round(12).tolist()
    [[0.0, 0.0], [0.0, 15.0], [0.0, 0.0]]
    """
    times, speed = validate.as_vector("t", t), validate.non_negative("speed", speed)
    start, duration = validate.number("start", start), validate.positive("duration", duration)
    direction = validate.number("direction", direction)
    return np.outer(((times >= start) & (times < start + duration)) * speed, [np.cos(direction), np.sin(direction)])
