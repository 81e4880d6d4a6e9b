"""Effort models on disk: one ``.npz`` of plain arrays (``allow_pickle=False``) with a JSON
header — never a pickle. The shipped default lives beside this module
(``laban/models/default.npz``, made by ``doodle laban train --synthetic``).

Arrays: ``nb_<factor>_{features,lo,hi,means,variances}`` for the three Naive Bayes
classifiers, ``drive_*`` and ``element_*`` for the two HMM sets
(``start, transitions, means, variances, centre, scale``), ``factor_<time|weight>_*`` for the
calibrated Time and Weight classifiers that decide the qualities applied
(``centre, scale, coef`` over the Effort features, ``bias`` and ``temperature`` single
numbers; :mod:`laban.factors`); ``meta`` holds the JSON header: format name and version, the
HMM labels, feature sets and points, the summary and Effort feature names the columns refer
to, the HMM temperature, the abstention threshold, and how it was trained.
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from doodle.core.errors import DoodleError
from doodle.core.files import atomic_write
from doodle.core.npz import read_npz
from laban.bayes import Binary
from laban.efforts import DRIVES, ELEMENTS, FACTORS
from laban.factors import Logistic
from laban.features import EFFORT_NAMES, FEATURE_SETS, SUMMARY_NAMES
from laban.hmm import HMMSet

FORMAT, VERSION = "doodle-laban-model", 2
DEFAULT = Path(__file__).resolve().parent / "models" / "default.npz"
HMM_FIELDS = ("start", "transitions", "means", "variances", "centre", "scale")
NB_FIELDS = ("features", "lo", "hi", "means", "variances")
FACTOR_FIELDS = ("centre", "scale", "coef", "bias", "temperature")
DECIDED = ("time", "weight")  # the Factors whose qualities are applied (thesis §4.4.3)
# What a model's numbers may be: HMM features are on a signed log scale and Naive Bayes ones
# scaled to [0, 1] (a few units either way), the bounds of raw summary features within
# RAW_LIMIT; these bounds only keep a corrupt file from overflowing the scoring (squares,
# reciprocals).
LIMIT = 1e6
RAW_LIMIT = 1e12
MIN_VARIANCE = 1e-15  # below it a variance is rounding noise (laban.selection.ZERO), not a spread
MIN_SPAN = 1e-9  # Naive Bayes bounds: features are divided by hi − lo
MAX_POINTS = 1 << 16  # HMM sequence length: the shipped 512, and room to spare


@dataclass(frozen=True, eq=False)
class EffortModel:
    """Everything that classifies a segment's Effort."""

    bayes: dict  # factor → laban.bayes.Binary
    drives: HMMSet
    elements: HMMSet
    sets: tuple[str, ...]
    points: int
    temperature: float = 1.0  # divides HMM log-likelihoods before the softmax (calibrated)
    threshold: float = 0.6  # a quality under this confidence is left neutral
    info: dict = field(default_factory=dict)
    factors: dict = field(default_factory=dict)  # "time", "weight" → laban.factors.Logistic


def save(model: EffortModel, path) -> Path:
    """Write ``model`` atomically to ``path`` (.npz)."""
    arrays = {}
    for factor, nb in model.bayes.items():
        for name in NB_FIELDS:
            arrays[f"nb_{factor}_{name}"] = np.asarray(getattr(nb, name))
    for prefix, hs in (("drive", model.drives), ("element", model.elements)):
        for name in HMM_FIELDS:
            arrays[f"{prefix}_{name}"] = np.asarray(getattr(hs, name), dtype=float)
    for factor in DECIDED:
        for name in FACTOR_FIELDS:
            arrays[f"factor_{factor}_{name}"] = np.asarray(getattr(model.factors[factor], name), dtype=float)
    meta = {"format": FORMAT, "version": VERSION, "drive_labels": list(model.drives.labels),
            "element_labels": list(model.elements.labels), "sets": list(model.sets), "points": model.points,
            "summary_names": list(SUMMARY_NAMES), "effort_names": list(EFFORT_NAMES), "factors": list(model.bayes),
            "temperature": model.temperature,
            "threshold": model.threshold, "info": model.info}
    arrays["meta"] = np.array(json.dumps(meta))
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    atomic_write(Path(path), buf.getvalue())
    return Path(path)


def load(path=None) -> EffortModel:
    """Read a model (the shipped default without ``path``); a corrupt, foreign or
    mismatched file is a :class:`DoodleError` naming the file and, for a bad array or header
    entry, that field and what is wrong with it — checked here, once, so that a model that
    loads scores any curve without NaN, overflow or a mismatch of shapes."""
    path = Path(path) if path is not None else DEFAULT
    where = str(path)
    if not path.exists():
        raise DoodleError(f"{where}: no such model file")
    arrays = read_npz(path)
    meta = _meta(arrays, where)
    sets = meta["sets"]
    width = sum(len(FEATURE_SETS[s]) for s in sets)
    bayes = {factor: _bayes(arrays, factor, where) for factor in meta["factors"]}
    hmms = [_hmms(arrays, prefix, meta[f"{prefix}_labels"], width, where) for prefix in ("drive", "element")]
    factors = {factor: _factor(arrays, factor, where) for factor in DECIDED}
    return EffortModel(bayes, hmms[0], hmms[1], sets, meta["points"], meta["temperature"], meta["threshold"],
                       meta["info"], factors)


def _meta(arrays: dict, where: str) -> dict:
    """The JSON header, every entry the program relies on checked (and normalised)."""
    raw = arrays.get("meta")
    if raw is None or raw.shape != () or raw.dtype.kind != "U":
        raise DoodleError(f"{where}: no valid 'meta' header: not a {FORMAT} file")
    try:
        meta = json.loads(str(raw))
    except (json.JSONDecodeError, RecursionError):
        meta = None
    if not isinstance(meta, dict):
        raise DoodleError(f"{where}: no valid 'meta' header: not a {FORMAT} file")
    if meta.get("format") != FORMAT:
        raise DoodleError(f"{where}: not a {FORMAT} file (format {meta.get('format')!r})")
    if meta.get("version") != VERSION:
        raise DoodleError(f"{where}: model version {meta.get('version')!r}; this program reads version {VERSION}")
    if meta.get("summary_names") != list(SUMMARY_NAMES):
        raise DoodleError(f"{where}: made with other summary features than this program computes; retrain it")
    if meta.get("effort_names") != list(EFFORT_NAMES):
        raise DoodleError(f"{where}: made with other Effort features than this program computes; retrain it")
    sets = meta.get("sets")
    if not _strings(sets) or not sets or not set(sets) <= set(FEATURE_SETS) or len(set(sets)) != len(sets):
        raise DoodleError(f"{where}: 'sets' must name feature sets among {sorted(FEATURE_SETS)}, got {sets!r}")
    elements = tuple(e for f in FACTORS for e in ELEMENTS[f])
    for key, known in (("factors", FACTORS), ("drive_labels", tuple(DRIVES)), ("element_labels", elements)):
        value = meta.get(key)
        if not _strings(value) or sorted(value) != sorted(known):
            raise DoodleError(f"{where}: {key!r} must list each of {', '.join(known)} once, got {value!r}")
    out = {"sets": tuple(sets), "factors": meta["factors"], "drive_labels": tuple(meta["drive_labels"]),
           "element_labels": tuple(meta["element_labels"]), "info": meta.get("info", {})}
    for key, kind, lo, hi in (("points", int, 8, MAX_POINTS), ("temperature", float, 1e-3, 1e9),
                              ("threshold", float, 0.5, 1.0)):
        value = meta.get(key)
        if isinstance(value, bool) or not isinstance(value, int if kind is int else (int, float)) \
                or not lo <= value <= hi:
            raise DoodleError(f"{where}: {key!r} must be a{'n integer' if kind is int else ' number'} "
                              f"from {lo:g} to {hi:g}, got {value!r}")
        out[key] = kind(value)
    if not isinstance(out["info"], dict):
        out["info"] = {}
    return out


def _strings(value) -> bool:
    return isinstance(value, list) and all(isinstance(v, str) for v in value)


def _array(arrays: dict, key: str, shape: tuple, where: str, lo: float = -LIMIT, hi: float = LIMIT) -> np.ndarray:
    """Array ``key``, of ``shape`` (None: any length) and real values in [lo, hi], as floats."""
    if key not in arrays:
        raise DoodleError(f"{where}: array {key!r} is missing")
    a = arrays[key]
    if a.dtype.kind not in "fiu" or a.ndim != len(shape) or any(s not in (None, n) for s, n in zip(shape, a.shape)):
        want = "×".join("n" if s is None else str(s) for s in shape) or "a single number"
        raise DoodleError(f"{where}: array {key!r} must be numbers shaped {want}, got {a.dtype} {a.shape}")
    a = a.astype(float)
    bad = ~(np.isfinite(a) & (a >= lo) & (a <= hi))
    if bad.any():
        at = tuple(int(i) for i in np.argwhere(bad)[0])
        raise DoodleError(f"{where}: array {key!r} holds {float(a[at]):g} at {at}; its values must be finite, "
                          f"from {lo:g} to {hi:g}")
    return a


def _bayes(arrays: dict, factor: str, where: str) -> Binary:
    """One Factor's Naive Bayes classifier: selected columns, bounds, class means and variances."""
    f = _array(arrays, f"nb_{factor}_features", (None,), where, 0, len(SUMMARY_NAMES) - 1)
    k = len(f)
    if not k or (f != np.round(f)).any():
        raise DoodleError(f"{where}: array 'nb_{factor}_features' must hold one or more whole column numbers")
    lo, hi = (_array(arrays, f"nb_{factor}_{n}", (k,), where, -RAW_LIMIT, RAW_LIMIT) for n in ("lo", "hi"))
    span = hi - lo
    if ((span != 0) & (span < MIN_SPAN)).any():  # a constant feature's bounds are equal; others apart
        raise DoodleError(f"{where}: arrays 'nb_{factor}_lo' and 'nb_{factor}_hi': each upper bound must equal its "
                          f"lower bound or be at least {MIN_SPAN:g} above it")
    means = _array(arrays, f"nb_{factor}_means", (2, k), where)
    variances = _array(arrays, f"nb_{factor}_variances", (2, k), where, MIN_VARIANCE, LIMIT)
    return Binary(f.astype(int), lo, hi, means, variances)


def _hmms(arrays: dict, prefix: str, labels: tuple, width: int, where: str) -> HMMSet:
    """The Drive or Element HMMs: ``m`` models of ``S`` states on ``width`` features."""
    m = len(labels)
    start = _array(arrays, f"{prefix}_start", (m, None), where, 0.0, 1.0)
    S = start.shape[1]
    A = _array(arrays, f"{prefix}_transitions", (m, S, S), where, 0.0, 1.0)
    for key, p in ((f"{prefix}_start", start), (f"{prefix}_transitions", A)):
        if not S or np.abs(p.sum(axis=-1) - 1.0).max() > 1e-6:
            raise DoodleError(f"{where}: array {key!r}: probabilities must sum to 1 (each row)")
    mu = _array(arrays, f"{prefix}_means", (m, S, width), where)
    var = _array(arrays, f"{prefix}_variances", (m, S, width), where, MIN_VARIANCE, LIMIT)
    centre = _array(arrays, f"{prefix}_centre", (width,), where)
    scale = _array(arrays, f"{prefix}_scale", (width,), where, MIN_VARIANCE, LIMIT)
    return HMMSet(labels, start, A, mu, var, centre, scale)


def _factor(arrays: dict, factor: str, where: str) -> Logistic:
    """One Factor's calibrated logistic classifier over the Effort features."""
    d = len(EFFORT_NAMES)
    centre, coef = (_array(arrays, f"factor_{factor}_{n}", (d,), where) for n in ("centre", "coef"))
    scale = _array(arrays, f"factor_{factor}_scale", (d,), where, MIN_SPAN, LIMIT)
    bias = _array(arrays, f"factor_{factor}_bias", (), where)
    temperature = _array(arrays, f"factor_{factor}_temperature", (), where, 1e-3, 1e3)
    return Logistic(centre, scale, coef, float(bias), float(temperature))
