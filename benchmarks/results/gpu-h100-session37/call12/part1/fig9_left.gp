set terminal pngcairo size 1000,600 noenhanced
set output 'fig9_left.png'
set title 'Cloth over sphere: update + queries per frame (kDet solid: the queries FCL answers)'
set xlabel 'triangles'
set ylabel 'ms per frame'
set logscale xy
set key outside right
set grid
plot 'fig9_left.dat' using 1:2 with linespoints lw 2 title 'kDet CPU 1T (same queries as FCL)', 'fig9_left.dat' using 1:3 with linespoints lw 2 title 'kDet GPU (same queries as FCL)', 'fig9_left.dat' using 1:4 with linespoints lw 2 title 'GPU BVH'
