# particles: seeding, binning and migration; P2G kernel sum, P2G -> G2P, advection and solid push-out.
pff_add_unit(test_particles RANKS 1 2 4)
pff_add_unit(test_particles_transfer RANKS 1 2 4)
