# quadtree tall cells: still water at rest and hydrostatic (cubic, tall, quadtree), SPD on random quadtrees,
# divergence-free projection, partition independence against one rank, bad input. At 1, 2 and 4 ranks.
pff_add_unit(test_tallcell RANKS 1 2 4)
