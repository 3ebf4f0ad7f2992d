"""Array, matrix and covariance checks of :mod:`fdikit.validate`.

Each helper checks one argument, returns it in canonical form (a float, an int, a read-only
float array ...) and otherwise raises an :mod:`fdikit.errors` class whose message names the
argument, says what is wrong and how to fix it.  The class defaults to
:class:`~fdikit.errors.ParameterError` (a bad argument); model constructors pass
``error=ModelError`` (a malformed model) and data readers ``error=DataError``.  The scalar, option
and type checks are in :mod:`fdikit.validate.scalars`; import every check from the package
:mod:`fdikit.validate`.

Examples
--------
>>> from fdikit.validate import as_matrix, positive
>>> as_matrix("L", [[1.0, 2.0]], (1, 2)).shape
(1, 2)
>>> positive("dt", 0.0)
Traceback (most recent call last):
...
fdikit.errors.ParameterError: dt must be a positive number, got 0.0
"""

from __future__ import annotations

import numpy as np

from fdikit.errors import ParameterError
from fdikit.validate.scalars import shown

__all__ = [
    "as_array",
    "as_matrix",
    "as_square",
    "as_vector",
    "as_complex_vector",
    "as_covariance",
    "noise_covariance",
    "psd_part",
]


def as_array(name: str, value, *, error: type[Exception] = ParameterError, finite: bool = True,
             complex_ok: bool = False) -> np.ndarray:
    """``value`` as a float array (any number of dimensions); strings, ragged input and (unless ``complex_ok``,
    which gives a complex array) complex entries are refused.

    Parameters
    ----------
    name : str
        The argument's name, as the messages quote it.
    value : array_like
        A number or a (nested) sequence or array of numbers; bools and integers become floats.
    error : exception class, default ParameterError
        Raised on failure (``ModelError``, ``DataError`` ... for other callers).
    finite : bool, default True
        Refuse NaN and ±inf entries (the message gives the first one's position).
    complex_ok : bool, default False
        Accept complex entries (the result is then complex).

    Returns
    -------
    ndarray
        A new float (or complex) array of the input's shape.

    Raises
    ------
    ParameterError
        (or ``error``) For None, a string, ragged or non-numeric input, complex entries (unless
        ``complex_ok``) or a non-finite entry (when ``finite``).

    Examples
    --------
    >>> from fdikit.validate import as_array
    >>> as_array("x", [[1, 2], [3, 4]]).dtype
    dtype('float64')
    """
    if value is None:
        raise error(f"{name} is required (got None); pass an array of numbers")
    if isinstance(value, str | bytes):
        raise error(f"{name} must be a number or an array of numbers, got the string {shown(value)}")
    try:
        raw = np.asarray(value)
    except (ValueError, TypeError) as exc:
        raise error(f"{name} must be a rectangular array of numbers (got {shown(value)}: {exc})") from None
    if raw.dtype == object:
        raise error(f"{name} must be a rectangular array of numbers, got {shown(value)} (ragged rows or objects)")
    if np.iscomplexobj(raw) and not complex_ok:
        raise error(f"{name} must be real; it has complex entries ({shown(value)})")
    if raw.dtype.kind not in "biufc":
        raise error(f"{name} must be an array of numbers, got entries of type {raw.dtype} ({shown(value)})")
    out = raw.astype(complex if np.iscomplexobj(raw) else float, copy=True)
    if finite and not np.all(np.isfinite(out)):
        # np.argwhere of a 0-d array has no columns (its size is 0 even for NaN): test the whole array first
        where = tuple(int(i) for i in np.argwhere(~np.isfinite(out))[0])
        at = f" at row {where[0]}, column {where[1]}" if out.ndim == 2 else f" at index {where}" if out.ndim else ""
        raise error(f"{name} has a non-finite entry{at} ({out[where]!r}); every entry must be a finite number")
    return out


def as_matrix(
    name: str,
    value,
    shape: tuple[int | None, int | None] | None = None,
    *,
    error: type[Exception] = ParameterError,
    finite: bool = True,
    scalar_ok: bool = False,
    promote: bool = False,
    complex_ok: bool = False,
) -> np.ndarray:
    """``value`` as a 2-D float matrix of ``shape`` (``None`` entries are free).

    A scalar becomes 1 x 1 (or, with ``scalar_ok`` and a square ``shape``, ``value · I``); with
    ``promote`` a vector becomes one row (``np.atleast_2d``); with ``complex_ok`` complex entries
    give a complex matrix.

    Parameters
    ----------
    name : str
        The argument's name, as the messages quote it.
    value : array_like
        A scalar or a 2-D array of numbers (a 1-D one only with ``promote``).
    shape : (int or None, int or None), optional
        Required rows and columns; ``None`` (the default, or an entry) leaves that size free.
    error : exception class, default ParameterError
        Raised on failure.
    finite : bool, default True
        Refuse NaN and ±inf entries.
    scalar_ok : bool, default False
        A scalar with a square ``shape`` means ``value · I``.
    promote : bool, default False
        A 1-D vector becomes a 1 x k row.
    complex_ok : bool, default False
        Accept complex entries.

    Returns
    -------
    (rows, cols) ndarray

    Raises
    ------
    ParameterError
        (or ``error``) As :func:`as_array`, and for an array that is not 2-D or has the wrong
        number of rows or columns (the message gives the shape wanted).

    Examples
    --------
    >>> from fdikit.validate import as_matrix
    >>> as_matrix("Q", 2.0, (2, 2), scalar_ok=True).tolist()
    [[2.0, 0.0], [0.0, 2.0]]
    >>> as_matrix("c", [1, 0, 0], (1, 3), promote=True).shape
    (1, 3)
    """
    out = as_array(name, value, error=error, finite=finite, complex_ok=complex_ok)
    rows, cols = shape if shape is not None else (None, None)
    if promote and out.ndim == 1:
        out = out.reshape(1, -1)
    if out.ndim == 0:
        if scalar_ok and rows is not None and rows == cols:
            out = float(out) * np.eye(rows)
        else:
            out = out.reshape(1, 1)
    if out.ndim != 2:
        raise error(f"{name} must be a 2-D matrix, got an array with {out.ndim} dimensions (shape {out.shape})")
    want = f"{'n' if rows is None else rows} x {'m' if cols is None else cols}"
    if rows is not None and out.shape[0] != rows:
        raise error(f"{name} has {out.shape[0]} rows but must have {rows} (shape {out.shape}); pass a {want} matrix")
    if cols is not None and out.shape[1] != cols:
        raise error(f"{name} has {out.shape[1]} columns but must have {cols} (shape {out.shape}); pass a {want} "
                    "matrix")
    return out


def as_square(name: str, value, n: int | None = None, *, error: type[Exception] = ParameterError) -> np.ndarray:
    """A finite square matrix (``n x n`` when ``n`` is given).

    Parameters
    ----------
    name : str
        The argument's name, as the messages quote it.
    value : array_like
        A square matrix of numbers (a scalar is 1 x 1).
    n : int, optional
        Required size (any when omitted).
    error : exception class, default ParameterError
        Raised on failure.

    Returns
    -------
    (n, n) ndarray

    Raises
    ------
    ParameterError
        (or ``error``) As :func:`as_matrix`, and for a matrix that is not square or not ``n x n``.

    Examples
    --------
    >>> from fdikit.validate import as_square
    >>> as_square("A", [[0, 1], [-2, -3]], 2).shape
    (2, 2)
    """
    out = as_matrix(name, value, error=error)
    if out.shape[0] != out.shape[1]:
        raise error(f"{name} must be square, got shape {out.shape}")
    if n is not None and out.shape[0] != n:
        raise error(f"{name} must be {n} x {n}, got shape {out.shape}")
    return out


def as_vector(name: str, value, size: int | None = None, *, error: type[Exception] = ParameterError,
              finite: bool = True) -> np.ndarray:
    """A 1-D float vector (a column or row matrix is flattened) of ``size`` entries.

    Parameters
    ----------
    name : str
        The argument's name, as the messages quote it.
    value : array_like
        A scalar (one entry), a 1-D sequence, or an array with at most one dimension longer than 1.
    size : int, optional
        Required number of entries (any when omitted).
    error : exception class, default ParameterError
        Raised on failure.
    finite : bool, default True
        Refuse NaN and ±inf entries.

    Returns
    -------
    (size,) ndarray

    Raises
    ------
    ParameterError
        (or ``error``) As :func:`as_array`, and for a true matrix or the wrong number of entries.

    Examples
    --------
    >>> from fdikit.validate import as_vector
    >>> as_vector("x0", [[1.0], [2.0]], 2).tolist()
    [1.0, 2.0]
    """
    out = as_array(name, value, error=error, finite=finite)
    if out.ndim > 1 and sum(d > 1 for d in out.shape) <= 1:
        out = out.reshape(-1)
    if out.ndim == 0:
        out = out.reshape(1)
    if out.ndim != 1:
        raise error(f"{name} must be a 1-D vector, got shape {out.shape}")
    if size is not None and out.size != size:
        raise error(f"{name} has {out.size} entries but must have {size}; pass a vector of length {size}")
    return out


def as_complex_vector(name: str, value, size: int | None = None, *,
                      error: type[Exception] = ParameterError) -> np.ndarray:
    """Finite complex numbers (poles, eigenvalues) as a 1-D complex vector of ``size`` entries.

    Parameters
    ----------
    name : str
        The argument's name, as the messages quote it.
    value : complex or sequence of complex
        A number or a 1-D sequence of real or complex numbers.
    size : int, optional
        Required number of entries (any when omitted).
    error : exception class, default ParameterError
        Raised on failure.

    Returns
    -------
    (size,) complex ndarray

    Raises
    ------
    ParameterError
        (or ``error``) For None, a string, non-numbers, more than one dimension, the wrong number
        of entries or a non-finite entry.

    Examples
    --------
    >>> from fdikit.validate import as_complex_vector
    >>> as_complex_vector("poles", [-1, -2 + 1j, -2 - 1j], 3).tolist()
    [(-1+0j), (-2+1j), (-2-1j)]
    """
    if isinstance(value, str | bytes) or value is None:
        raise error(f"{name} must be a sequence of numbers, got {shown(value)}")
    try:
        out = np.atleast_1d(np.asarray(value, dtype=complex))
    except (TypeError, ValueError) as exc:
        raise error(f"{name} must be a sequence of numbers ({exc})") from None
    if out.ndim != 1:
        raise error(f"{name} must be a 1-D sequence of numbers, got shape {out.shape}")
    if size is not None and out.size != size:
        raise error(f"{name} has {out.size} entries but must have {size}")
    if not np.all(np.isfinite(out)):
        raise error(f"{name} must be finite numbers, got {out.tolist()}")
    return out


def as_covariance(
    name: str,
    value,
    n: int,
    *,
    error: type[Exception] = ParameterError,
    definite: bool = False,
    scalar_ok: bool = True,
    diagonal_ok: bool = False,
    rtol: float = 1e-12,
    psd_rtol: float | None = None,
) -> np.ndarray:
    """A symmetric positive semidefinite (``definite``: positive definite) ``n x n`` matrix.

    A scalar means ``value · I``; with ``diagonal_ok`` a vector of ``n`` variances means their
    diagonal matrix.  Symmetry and the eigenvalue test use a tolerance ``rtol`` relative to the
    largest entry (``psd_rtol``, when given, for the eigenvalues).  Returns the symmetric part.

    Parameters
    ----------
    name : str
        The argument's name, as the messages quote it.
    value : float, (n,) or (n, n) array_like
        The covariance (a scalar only with ``scalar_ok``, a vector only with ``diagonal_ok``).
    n : int
        Size of the covariance.
    error : exception class, default ParameterError
        Raised on failure.
    definite : bool, default False
        Require the smallest eigenvalue to be > 0.
    scalar_ok : bool, default True
        A scalar means ``value · I``.
    diagonal_ok : bool, default False
        A vector of ``n`` variances means their diagonal matrix.
    rtol : float, default 1e-12
        Tolerance of the symmetry and eigenvalue tests, relative to the largest entry.
    psd_rtol : float, optional
        Tolerance of the eigenvalue test alone (``rtol`` when omitted).

    Returns
    -------
    (n, n) ndarray
        The symmetric part ``(M + M.T) / 2``.

    Raises
    ------
    ParameterError
        (or ``error``) As :func:`as_array`, and for the wrong shape, an asymmetric matrix, a
        negative eigenvalue beyond the tolerance, or (``definite``) one that is not > 0.

    Examples
    --------
    >>> from fdikit.validate import as_covariance
    >>> as_covariance("R", [0.01, 0.04], 2, diagonal_ok=True).tolist()
    [[0.01, 0.0], [0.0, 0.04]]
    >>> as_covariance("R", [[1.0, 2.0], [2.0, 1.0]], 2)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    fdikit.errors.ParameterError: R must be positive semidefinite (smallest eigenvalue -1); ...
    """
    raw = as_array(name, value, error=error)
    if scalar_ok and raw.size == 1 and raw.ndim <= 2:
        raw = raw.reshape(())
    if diagonal_ok and raw.ndim == 1 and raw.size == n:
        raw = np.diag(raw)
    if raw.shape != (n, n) and not (raw.ndim == 0 and (scalar_ok or n == 1)):
        kinds = " (a scalar means σ² I)" if scalar_ok else ""
        kinds = f" (a scalar means σ² I, {n} variances their diagonal)" if diagonal_ok else kinds
        raise error(f"{name} must be a {n}x{n} covariance matrix{kinds}; use np.diag(variances) for independent "
                    f"components; got shape {raw.shape}")
    out = as_matrix(name, raw, (n, n), error=error, scalar_ok=scalar_ok)
    scale = float(np.abs(out).max(initial=0.0))  # relative to the data: a covariance of 1e-8 rad² is judged as one of 1
    if not np.allclose(out, out.T, rtol=0.0, atol=rtol * scale):
        raise error(f"{name} must be symmetric; pass (M + M.T) / 2 or a diagonal matrix")
    out = (out + out.T) / 2
    if n:
        low = float(np.linalg.eigvalsh(out)[0])
        if definite and low <= 0:
            raise error(
                f"{name} must be positive definite (smallest eigenvalue {low:.3g}); add a small positive diagonal"
            )
        if low < -(rtol if psd_rtol is None else psd_rtol) * scale:
            raise error(f"{name} must be positive semidefinite (smallest eigenvalue {low:.3g}); "
                        "a covariance has non-negative eigenvalues")
    return out


def noise_covariance(std_name: str, std, cov_name: str, cov, k: int, what: str = "signal", *,
                     error: type[Exception] = ParameterError) -> np.ndarray | None:
    """The ``k x k`` covariance of ``k`` noise signals given either as a standard deviation or as a covariance.

    The std/cov convention of ``docs/ARCHITECTURE.md``.  A std of ``s`` and a cov of ``s**2`` give the
    same matrix, bit for bit.

    Parameters
    ----------
    std_name, cov_name : str
        The two parameter names, as the messages quote them (``"noise_std"``, ``"noise_cov"``).
    std : float, (k,) array_like or None
        Standard deviations σ (a scalar for every signal, or one per signal), finite and >= 0.
    cov : float, (k,) or (k, k) array_like or None
        A covariance: a variance for every signal (``σ² I``), ``k`` variances (``diag``) or a
        symmetric positive semidefinite ``k x k`` matrix.
    k : int
        Number of noise signals.
    what : str, default "signal"
        What one signal is, for the messages ("output", "state" ...).
    error : exception class, default ParameterError

    Returns
    -------
    (k, k) ndarray or None
        The covariance, or None when neither is given.

    Raises
    ------
    ParameterError
        (or ``error``) When both are given, or the one given is not finite, of the wrong size or shape,
        negative, asymmetric or not positive semidefinite.

    Examples
    --------
    >>> from fdikit.validate import noise_covariance
    >>> noise_covariance("v_std", [0.1, 0.2], "v_cov", None, 2).round(3).tolist()
    [[0.01, 0.0], [0.0, 0.04]]
    >>> noise_covariance("v_std", None, "v_cov", 0.01, 2).tolist()
    [[0.01, 0.0], [0.0, 0.01]]
    """
    if std is not None and cov is not None:
        raise error(f"give {std_name} or {cov_name}, not both: {std_name} is a standard deviation σ (a scalar or one "
                    f"per {what}), {cov_name} a covariance σ² (a {k} x {k} matrix, or a scalar/vector meaning σ² I / "
                    "diag)")
    if std is None and cov is None:
        return None
    name, value = (std_name, std) if std is not None else (cov_name, cov)
    arr = as_array(name, value, error=error, finite=False)
    if not np.all(np.isfinite(arr)):
        raise error(f"{name} must be finite, got {shown(arr.tolist())}")
    if std is not None:
        if arr.ndim > 1:
            raise error(f"{name} is a standard deviation: a scalar or one per {what} ({k}), got an array of shape "
                        f"{arr.shape}; give a {k} x {k} covariance matrix as {cov_name}")
        if arr.size not in (1, k):
            raise error(f"{name} has {arr.size} standard deviations; need 1 or {k} (one per {what})")
        if np.any(arr < 0):
            raise error(f"{name} holds standard deviations, which must be >= 0; got {shown(arr.tolist())}")
        return np.diag(np.broadcast_to(arr, (k,)) ** 2)
    if arr.ndim <= 1:
        if arr.size not in (1, k):
            raise error(f"{name} has {arr.size} variances; need 1 or {k} (one per {what}) or a {k} x {k} "
                        "covariance matrix")
        if np.any(arr < 0):
            raise error(f"{name} holds variances σ² (a scalar or vector means σ² I / diag), which must be >= 0; "
                        f"got {shown(arr.tolist())}")
        return np.diag(np.broadcast_to(arr, (k,)))
    return as_covariance(name, arr, k, error=error, scalar_ok=False)


def psd_part(name: str, M, *, error: type[Exception] = ParameterError) -> np.ndarray:
    """Symmetric part of the square covariance ``M``: :func:`as_covariance` with the tolerances of the Kalman
    steps (symmetry to 1e-8, eigenvalues to −1e-10 of the largest entry).

    Parameters
    ----------
    name : str
        The argument's name, as the error message quotes it.
    M : array_like
        A square covariance matrix (its size is taken from ``M``).
    error : type, optional
        The error class to raise (default :class:`~fdikit.errors.ParameterError`).

    Returns
    -------
    numpy.ndarray
        ``(M + Mᵀ) / 2``.

    Raises
    ------
    ParameterError
        (or ``error``) for a non-square, asymmetric or indefinite ``M``.

    Examples
    --------
    >>> psd_part("P0", [[2.0, 0.5], [0.5, 1.0]]).tolist()
    [[2.0, 0.5], [0.5, 1.0]]
    """
    M = as_array(name, M, error=error)
    return as_covariance(name, M, M.shape[0] if M.ndim else 1, error=error, scalar_ok=False, rtol=1e-8,
                         psd_rtol=1e-10)
