# pressure: operator (symmetry, row sums, the 7-point limit), projection with every PC on uniform and
# graded grids (closed and periodic), partition independence, hydrostatic balance. At 1, 2 and 4 ranks.
pff_add_unit(test_pressure RANKS 1 2 4)
