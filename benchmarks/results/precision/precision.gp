# gnuplot precision.gp (in this folder) -> precision.png
set terminal pngcairo size 1400,650 noenhanced font ',10'
set output 'precision.png'
set multiplot layout 1,2 title "kdet_fcl predicate modes: time vs errors, one point per scene (CPU: AMD EPYC; GPU: skipped (built without CUDA))"
set logscale x
set logscale y
set grid
set xrange [0.2497:2.113]
set yrange [0.7:2.38e+05]
set xtics (0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1, 1.5, 2, 3, 5, 10, 20, 50, 100)
set xlabel 'time per query / time of Predicate::Exact (same scene, mesh precision, backend)'
set ylabel 'misses + extras + 1 against the exact referee (1 = exact answer)'
set title 'generic scenes (cloth self, cloth vs sphere, random soup)'
set key top left box opaque
plot 'precision.dat' index 0 using ($5 == 0 ? $1*(1+0.015*(-3)) : 1/0):2 with points pt 7 ps 1.3 lc rgb '#1b7837' title 'cpu, double mesh, exact predicate', \
     'precision.dat' index 1 using ($5 == 0 ? $1*(1+0.015*(-2)) : 1/0):2 with points pt 7 ps 1.3 lc rgb '#2166ac' title 'cpu, double mesh, double predicate', \
     'precision.dat' index 2 using ($5 == 0 ? $1*(1+0.015*(-1)) : 1/0):2 with points pt 7 ps 1.3 lc rgb '#d6604d' title 'cpu, double mesh, float predicate', \
     'precision.dat' index 3 using ($5 == 0 ? $1*(1+0.015*(0)) : 1/0):2 with points pt 5 ps 1.3 lc rgb '#1b7837' title 'cpu, float mesh, exact predicate', \
     'precision.dat' index 4 using ($5 == 0 ? $1*(1+0.015*(1)) : 1/0):2 with points pt 5 ps 1.3 lc rgb '#2166ac' title 'cpu, float mesh, double predicate', \
     'precision.dat' index 5 using ($5 == 0 ? $1*(1+0.015*(2)) : 1/0):2 with points pt 5 ps 1.3 lc rgb '#d6604d' title 'cpu, float mesh, float predicate'
set title 'near-degenerate scenes (touching, coplanar, nearly parallel, far, slivers, extremes)'
unset key
plot 'precision.dat' index 0 using ($5 == 1 ? $1*(1+0.015*(-3)) : 1/0):2 with points pt 7 ps 1.3 lc rgb '#1b7837' title 'cpu, double mesh, exact predicate', \
     'precision.dat' index 1 using ($5 == 1 ? $1*(1+0.015*(-2)) : 1/0):2 with points pt 7 ps 1.3 lc rgb '#2166ac' title 'cpu, double mesh, double predicate', \
     'precision.dat' index 2 using ($5 == 1 ? $1*(1+0.015*(-1)) : 1/0):2 with points pt 7 ps 1.3 lc rgb '#d6604d' title 'cpu, double mesh, float predicate', \
     'precision.dat' index 3 using ($5 == 1 ? $1*(1+0.015*(0)) : 1/0):2 with points pt 5 ps 1.3 lc rgb '#1b7837' title 'cpu, float mesh, exact predicate', \
     'precision.dat' index 4 using ($5 == 1 ? $1*(1+0.015*(1)) : 1/0):2 with points pt 5 ps 1.3 lc rgb '#2166ac' title 'cpu, float mesh, double predicate', \
     'precision.dat' index 5 using ($5 == 1 ? $1*(1+0.015*(2)) : 1/0):2 with points pt 5 ps 1.3 lc rgb '#d6604d' title 'cpu, float mesh, float predicate'
unset multiplot
