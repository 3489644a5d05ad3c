set terminal pngcairo size 1000,600 noenhanced
set output 'fig9_right_fracture.png'
set title 'Fracturing sphere 57k: time per frame (frame 0 = build)'
set xlabel 'frame'
set ylabel 'ms per frame'
set logscale y
set xtics 1
set key outside right
set grid
plot 'fig9_right_fracture.dat' using 1:3 with linespoints lw 2 title 'kDet CPU 1T (same queries as FCL)', 'fig9_right_fracture.dat' using 1:4 with linespoints lw 2 title 'kDet CPU 2T (same queries as FCL)', 'fig9_right_fracture.dat' using 1:5 with linespoints lw 2 title 'kDet GPU (same queries as FCL)', 'fig9_right_fracture.dat' using 1:6 with linespoints lw 2 title 'FCL OBBRSS', 'fig9_right_fracture.dat' using 1:7 with linespoints lw 2 title 'GPU BVH', 'fig9_right_fracture.dat' using 1:8 with linespoints lw 2 dt 2 title 'kDet CPU 2T, with self-collision'
