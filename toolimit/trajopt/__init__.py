"""Stage (iii): sequential-QP (OSQP) tracking of a tool trajectory with base placement."""
