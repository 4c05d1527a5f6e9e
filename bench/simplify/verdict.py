"""The issue 3 quality verdict for one case, shared by report.py (the full run) and requality.py."""
import math

QUALITY_PEERS = ("cgal-gh", "meshopt")  # the "better of CGAL-GH and meshoptimizer"
TIE = 1e-7  # relative distances closer than this are equal (both tools exact on a flat part)


def stopped_short(triangles_out, target):
    """A tool that stopped well short of the target kept more triangles: an easier job, not comparable."""
    return triangles_out > 1.05 * target + 2


def judge(lodkit, reached, lodkit_short):
    """(verdict, ratio) for one quantity: "ok" (lodkit <= the best of `reached`, the values of the peers
    that reached the target), "worse" (with the ratio), "short" (lodkit stopped short where a peer did
    not: counts against lodkit), or None (no peer reached the target, or lodkit's value is missing:
    not a case)."""
    if lodkit is None or not reached:
        return None, None
    if lodkit_short:
        return "short", None
    best = min(reached)
    if lodkit <= best + TIE:
        return "ok", 1.0
    return "worse", lodkit / best if best > 0 else math.inf
