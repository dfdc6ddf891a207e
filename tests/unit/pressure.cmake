# pressure: operator (symmetry, row sums, the 7-point limit), projection with every PC on uniform and
# graded grids (closed and periodic), partition independence, hydrostatic balance. At 1, 2 and 4 ranks.
pff_add_unit(test_pressure RANKS 1 2 4)
# pffmg: Galerkin levels against explicit P^T A P and Algorithm 1's face sums, smoother energy decrease on
# every level, FCG + pffmg convergence on the bubbly problem (iterations rank-independent within 3),
# adaptive relaxation cheaper than fixed sweeps for a localised residual, matrix-free levels equal to the
# AIJ Galerkin levels. At 1, 2 and 4 ranks, and with 2 threads.
pff_add_unit(test_pffmg RANKS 1 2 4)
pff_add_unit(test_pffmg RANKS 2 THREADS 2 ARGS -pressure_pffmg_omp_min_rows 0) # threads on every level of the small grids
# pressure with Dirichlet walls: symmetric, definite (no null space), exact for p = distance to the wall on
# uniform and graded grids, CG on a nonzero-mean rhs, partition independence, bad input. At 1, 2 and 4 ranks.
pff_add_unit(test_pressure_dirichlet RANKS 1 2 4)
# matrix-free operator: S x = A x and diag S = diag A on uniform, graded, periodic, closed and inactive grids
# with random beta and closed faces; Jacobi-CG with (S, S) as with (A, A); projection with
# -pressure_operator shell as with aij (pffmg and jacobi), also with Dirichlet walls. At 1, 2 and 4 ranks.
pff_add_unit(test_pressure_shell RANKS 1 2 4)
# memory-traffic count of a solve (the bench's ITERATION/TRAFFIC lines) against the Vec and Mat operations PETSc
# logged in a stage around an FCG solve: default, wrapped and standard truncation; unknown for CG. At 1, 2 and 4 ranks.
pff_add_unit(test_pressure_traffic RANKS 1 2 4)
