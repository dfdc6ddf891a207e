# particles: seeding, binning and migration; P2G kernel sum, P2G -> G2P, advection and solid push-out.
pff_add_unit(test_particles RANKS 1 2 4)
pff_add_unit(test_particles_transfer RANKS 1 2 4)
# G2P and advection sample in threads over blocks and points, P2G splats in colours (issue 12)
pff_add_unit(test_particles_transfer RANKS 1 2 THREADS 2)
# the cell-centre volume of the two-phase correction: conservation across levels, lattice values, weights
pff_add_unit(test_particles_volume RANKS 1 2 4)
pff_add_unit(test_particles_volume RANKS 2 THREADS 2)
# particles: split (mass and momentum exact, one child per fine sub-cell) and probabilistic coarsening (survival
# rates within 5 sigma, hysteresis, the same survivors on any rank and thread count).
pff_add_unit(test_particles_adapt RANKS 1 2 4)
pff_add_unit(test_particles_adapt RANKS 2 THREADS 2)
