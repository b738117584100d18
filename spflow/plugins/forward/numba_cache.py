"""Keep numba's on-disk cache of the forward kernels consistent with their sources.

numba's ``cache=True`` keys a cached function on the source file that defines it, not on the files of the functions
it calls and inlines. The time-loop kernel inlines the property kernels of ``physics/`` and the helpers of this
package, so an edit in one of those files would otherwise leave a stale compiled kernel in ``__pycache__``.
``invalidate_stale_cache()`` hashes every source file of the forward model and, when the digest differs from the one
recorded next to the cache, deletes the cached numba objects (``*.nbi``, ``*.nbc``) of the forward model so that
numba recompiles them. It only touches files inside the package's own ``__pycache__`` directories.
"""

from __future__ import annotations

import hashlib
from functools import cache
from pathlib import Path

__all__ = ["invalidate_stale_cache", "source_digest"]

_ROOT = Path(__file__).resolve().parent
_STAMP = "spflow_forward_sources.sha256"


@cache
def source_digest() -> str:
    """SHA-256 over every source file of the forward model as loaded in this process (also keys the ``forward``
    stage's results)."""
    h = hashlib.sha256()
    for path in sorted(_ROOT.glob("*.py")) + sorted((_ROOT / "physics").glob("*.py")):
        h.update(path.relative_to(_ROOT).as_posix().encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def invalidate_stale_cache() -> bool:
    """Delete the forward model's numba cache if any source changed since it was written; True if deleted."""
    digest = source_digest()
    stamp = _ROOT / "__pycache__" / _STAMP
    try:
        if stamp.read_text() == digest:
            return False
    except OSError:
        pass
    # two_d's compiled functions call the 1-D helpers, so their cache goes stale with them (each two_d file's own
    # edits are tracked by numba: they call nothing else of two_d that is compiled)
    for folder in (_ROOT / "__pycache__", _ROOT / "physics" / "__pycache__", _ROOT / "two_d" / "__pycache__"):
        for pattern in ("*.nbi", "*.nbc"):
            for path in folder.glob(pattern):
                path.unlink(missing_ok=True)
    try:
        stamp.parent.mkdir(exist_ok=True)
        stamp.write_text(digest)
    except OSError:  # read-only install: numba then cannot cache either
        pass
    return True
