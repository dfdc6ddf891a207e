# flow: the viscosity of the FLIP/PIC blend (Eq. 13) from the decay of a shear wave.
pff_add_unit(test_flow_viscosity RANKS 1 2)
