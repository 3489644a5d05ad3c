set terminal pngcairo size 1100,500 noenhanced
set output 'kfree_boxplot.png'
set multiplot layout 1,2 title 'k-free study (Definition 3.1): Tukey box plots binned by triangle count'
set style data boxplot
set style boxplot outliers pointtype 7
set style fill solid 0.3 border -1
set boxwidth 0.5
set pointsize 0.5
set xlabel 'triangles'
set grid y
unset key
set logscale y
set ylabel 'minimum k (max neighbour count + 1)'
plot 'kfree_binned.dat' using (1.0):3:(0.5):2
unset logscale y
set ylabel 'mean neighbour count per triangle'
plot 'kfree_binned.dat' using (1.0):4:(0.5):2
unset multiplot
