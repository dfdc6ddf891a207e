# quadtree tall cells: still water at rest and hydrostatic (cubic, tall, quadtree), SPD on random quadtrees,
# divergence-free projection, partition independence against one rank, bad input. At 1, 2 and 4 ranks.
pff_add_unit(test_tallcell RANKS 1 2 4)
# solids in the tall-cell pressure: open fractions of cut faces, still water around obstacles on the four
# discretisations, two pools behind a wall, SPD with solids on random quadtrees. At 1, 2 and 4 ranks.
pff_add_unit(test_tallcell_solid RANKS 1 2 4)
# two-way coupled rigid bodies: Archimedes force on a held box, a buoyant box stays at rest in one coupled
# projection (Eq. 14), lighter rises, heavier sinks. At 1, 2 and 4 ranks.
pff_add_unit(test_tallcell_bodies RANKS 1 2 4)
