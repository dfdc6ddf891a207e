# flow: the viscosity of the FLIP/PIC blend (Eq. 13) from the decay of a shear wave.
pff_add_unit(test_flow_viscosity RANKS 1 2)
# flow: liquid-velocity extrapolation into the air (Sec. 3.7): slab layers, the layer rule against a serial
# reference, and two levels.
pff_add_unit(test_flow_extrapolate RANKS 1 2 4)
# flow: liquid and gas volumes of the fluid cells (PffFlowGetPhaseVolumes, issue 10): closed box half full, with a
# solid cube and on two levels; and the liquid volume's control over a step (the volume it holds, its clamp).
pff_add_unit(test_flow_volumes RANKS 1 2 4)
# flow: particles, pressure, pffmg and flow follow a grid adapt (topology state), against a grid set up on the new
# map; also threaded.
pff_add_unit(test_adapt_flow RANKS 1 2 4)
pff_add_unit(test_adapt_flow RANKS 2 THREADS 2)
# flow: the reference lattice made again after an adapt (changed blocks and slabs of their neighbours) equals the
# reference of a flow set up on the new map, in a closed box with a solid and periodic.
pff_add_unit(test_adapt_reference RANKS 1 2 4)
# flow: user regions force their level on blocks and particles, the vorticity criterion refines a spinning ball of
# air (issue 14); also threaded.
pff_add_unit(test_adapt_regions RANKS 1 2 4)
pff_add_unit(test_adapt_regions RANKS 2 THREADS 2)
# flow: a block coarsens only after its particles asked for it -adapt_coarsen_delay times in a row (a drop
# that appears and goes again)
pff_add_unit(test_adapt_hold RANKS 1 2 4)
pff_add_unit(test_adapt_hold RANKS 2 THREADS 2)
