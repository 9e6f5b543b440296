"""Reference methods: iterations of other kinds that the studies run beside the solver, never the default solve.

Each module is one published method, reconstructed to answer a study's question about solvers of its
kind (:mod:`.stanley_kato`: Stanley & Kato's (1997) displacement iteration, the family Yastrebov et al.
(2012) used, which the κ-gap study, :mod:`roughcontact.studies.kappa_gap`, runs against ours). Nothing
in :func:`~roughcontact.solver.solve_contact` or the pipeline's contact stage imports them; they are
imported from their modules, ``roughcontact.solver.reference.stanley_kato``.
"""
