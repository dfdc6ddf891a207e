# pff-bench-particles on a small closed tank (32^3 cells, walls on every axis, one repetition) at 1 and 2
# ranks: the walled paths of P2G, G2P and advection (tiles clamped at walls) run in threads over blocks and
# the benchmark prints its advection line (a crash, an error or a missing line fails). The kernels' results
# are checked in test_particles_transfer; this keeps the benchmark itself running.
pff_add_mpi_test(bench_particles_walls COMMAND $<TARGET_FILE:pff-bench-particles> -bench_n 32 -bench_reps 1 -bench_walls
                 RANKS 1 2 LABELS bench REGEX "RESULT kernel=advect ranks=[12] walls=1 particles=262144")
