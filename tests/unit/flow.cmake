# flow: the viscosity of the FLIP/PIC blend (Eq. 13) from the decay of a shear wave.
pff_add_unit(test_flow_viscosity RANKS 1 2)
# flow: liquid-velocity extrapolation into the air (Sec. 3.7): slab layers, the layer rule against a serial
# reference, and two levels.
pff_add_unit(test_flow_extrapolate RANKS 1 2 4)
