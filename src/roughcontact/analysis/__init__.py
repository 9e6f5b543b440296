"""Analysis of solved cases: aggregation over cases and seeds (:mod:`.aggregate`), CEL fits (:mod:`.fit`)."""
