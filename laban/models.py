"""Effort models on disk: one ``.npz`` of plain arrays (``allow_pickle=False``) with a JSON
header — never a pickle. The shipped default lives beside this module
(``laban/models/default.npz``, made by ``doodle laban train --synthetic``).

Arrays: ``nb_<factor>_{features,lo,hi,means,variances}`` for the three Naive Bayes
classifiers, ``drive_*`` and ``element_*`` for the two HMM sets
(``start, transitions, means, variances, centre, scale``); ``meta`` holds the JSON header:
format name and version, the HMM labels, feature sets and points, the summary feature names
the columns refer to, the temperature and threshold of the confidences, and how it was
trained.
"""

from __future__ import annotations

import io
import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from doodle.core.errors import DoodleError
from doodle.core.files import atomic_write
from laban.bayes import Binary
from laban.features import FEATURE_SETS, SUMMARY_NAMES
from laban.hmm import HMMSet

FORMAT, VERSION = "doodle-laban-model", 1
DEFAULT = Path(__file__).resolve().parent / "models" / "default.npz"
HMM_FIELDS = ("start", "transitions", "means", "variances", "centre", "scale")
NB_FIELDS = ("features", "lo", "hi", "means", "variances")


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


def save(model: EffortModel, path) -> Path:
    """Write ``model`` atomically to ``path`` (.npz)."""
    arrays = {}
    for factor, nb in model.bayes.items():
        for name in NB_FIELDS:
            arrays[f"nb_{factor}_{name}"] = np.asarray(getattr(nb, name))
    for prefix, hs in (("drive", model.drives), ("element", model.elements)):
        for name in HMM_FIELDS:
            arrays[f"{prefix}_{name}"] = np.asarray(getattr(hs, name), dtype=float)
    meta = {"format": FORMAT, "version": VERSION, "drive_labels": list(model.drives.labels),
            "element_labels": list(model.elements.labels), "sets": list(model.sets), "points": model.points,
            "summary_names": list(SUMMARY_NAMES), "factors": list(model.bayes), "temperature": model.temperature,
            "threshold": model.threshold, "info": model.info}
    arrays["meta"] = np.array(json.dumps(meta))
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    atomic_write(Path(path), buf.getvalue())
    return Path(path)


def load(path=None) -> EffortModel:
    """Read a model (the shipped default without ``path``); a corrupt, foreign or
    mismatched file is a :class:`DoodleError` naming the file and what is wrong."""
    path = Path(path) if path is not None else DEFAULT
    where = str(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
    except FileNotFoundError:
        raise DoodleError(f"{where}: no such model file") from None
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
        raise DoodleError(f"{where}: not a readable model file ({exc})") from None
    try:
        meta = json.loads(str(arrays["meta"]))
    except (KeyError, json.JSONDecodeError):
        raise DoodleError(f"{where}: no valid 'meta' header: not a {FORMAT} file") from None
    if meta.get("format") != FORMAT:
        raise DoodleError(f"{where}: not a {FORMAT} file (format {meta.get('format')!r})")
    if meta.get("version") != VERSION:
        raise DoodleError(f"{where}: model version {meta.get('version')!r}; this program reads version {VERSION}")
    if meta.get("summary_names") != list(SUMMARY_NAMES):
        raise DoodleError(f"{where}: made with other summary features than this program computes; retrain it")
    sets = tuple(meta.get("sets", ()))
    if not sets or any(s not in FEATURE_SETS for s in sets):
        raise DoodleError(f"{where}: 'sets' must name feature sets among {sorted(FEATURE_SETS)}, got {list(sets)}")
    width = sum(len(FEATURE_SETS[s]) for s in sets)

    def need(key):
        if key not in arrays:
            raise DoodleError(f"{where}: array {key!r} is missing")
        a = arrays[key]
        if a.dtype.kind not in "fiu" or not np.isfinite(a).all():
            raise DoodleError(f"{where}: array {key!r} is not finite numbers")
        return a

    bayes = {}
    for factor in meta.get("factors", []):
        f, lo, hi, mu, var = (need(f"nb_{factor}_{n}") for n in NB_FIELDS)
        k = len(f)
        if f.ndim != 1 or f.min(initial=0) < 0 or f.max(initial=0) >= len(SUMMARY_NAMES) or lo.shape != (k,) \
                or hi.shape != (k,) or mu.shape != (2, k) or var.shape != (2, k) or (var <= 0).any():
            raise DoodleError(f"{where}: Naive Bayes arrays for {factor!r} have inconsistent shapes or values")
        bayes[factor] = Binary(f.astype(int), lo, hi, mu, var)
    hmms = []
    for prefix in ("drive", "element"):
        labels = tuple(meta.get(f"{prefix}_labels", ()))
        start, A, mu, var, centre, scale = (need(f"{prefix}_{n}") for n in HMM_FIELDS)
        m = len(labels)
        if not m or start.ndim != 2 or start.shape[0] != m:
            raise DoodleError(f"{where}: {prefix} HMMs: {m} labels but start probabilities shaped {start.shape}")
        S = start.shape[1]
        if A.shape != (m, S, S) or mu.shape != (m, S, width) or var.shape != (m, S, width) \
                or centre.shape != (width,) or scale.shape != (width,) or (var <= 0).any() or (scale <= 0).any():
            raise DoodleError(f"{where}: {prefix} HMM arrays do not agree with {m} models of {S} states "
                              f"on {width} features")
        hmms.append(HMMSet(labels, start, A, mu, var, centre, scale))
    try:
        points, temperature, threshold = int(meta["points"]), float(meta["temperature"]), float(meta["threshold"])
    except (KeyError, TypeError, ValueError):
        raise DoodleError(f"{where}: 'points', 'temperature' and 'threshold' must be numbers") from None
    if points < 8 or temperature <= 0 or not 0.5 <= threshold <= 1.0:
        raise DoodleError(f"{where}: points ≥ 8, temperature > 0 and threshold in [0.5, 1] required")
    return EffortModel(bayes, hmms[0], hmms[1], sets, points, temperature, threshold, meta.get("info", {}))
