# Fig. 1(b) of the paper: the Carlson-Langer stick-slip law and the
# creep-slip law of the model, against block velocity (data: bkfront run,
# [friction]).
load plotdir.'/common.gp'
f = word(files, 1)
set title (title ne '' ? title : 'Friction laws (Fig. 1b)')
set xlabel 'block velocity v'
set ylabel 'friction force F / F_0'
set xzeroaxis lt -1 lw 0.5
set arrow from 0, graph 0 to 0, graph 1 nohead lc rgb '#777777' dt 3
set label 'slip threshold' at first 0, graph 0.93 offset 0.6, 0 tc rgb '#777777'
set key bottom right
# both laws whole over the table's velocities (the cubic creep-slip law
# leaves [-1, 1] past v = 3: the scenes draw v in [-1, 3])
set offsets 0, 0, graph 0.05, graph 0.05
plot f using 'v':'carlson_langer' with lines lw 2 lc rgb '#1f77b4' \
       title 'Carlson-Langer: sgn(v)/(1+|v|)', \
     f using 'v':'creep_slip' with lines lw 2 dt 2 lc rgb '#d62728' \
       title 'creep-slip: (3/2) {/Symbol f}(v-1), {/Symbol f}({/Symbol y}) = {/Symbol y}^3/3 - {/Symbol y}'
