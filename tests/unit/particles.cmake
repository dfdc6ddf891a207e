# particles: seeding, binning and migration; P2G kernel sum, P2G -> G2P, advection and solid push-out.
pff_add_unit(test_particles RANKS 1 2 4)
pff_add_unit(test_particles_transfer RANKS 1 2 4)
# G2P and advection sample in threads over blocks and points, P2G splats in colours (issue 12)
pff_add_unit(test_particles_transfer RANKS 1 2 THREADS 2)
