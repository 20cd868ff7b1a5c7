# Floquet dispersion relations lambda_q of the global oscillation, one curve
# per nu (Fig. 4a of the paper); the modes a system of size S allows are
# marked (data: bkfront floquet --q ... --S ...).
load plotdir.'/common.gp'
set title titled('Floquet exponent of the global oscillation', word(files, 1), 'gamma c')
Sv = input(word(files, 1), 'S')
set xlabel 'wavenumber q'
set ylabel 'growth per period {/Symbol l}_q'
set xzeroaxis lt -1 lw 1
set key bottom left
plot for [i=1:nfiles] word(files, i) using 'q':'lambda' with lines lw 2 \
       lc rgb color(i) title sprintf('{/Symbol n} = %s', word(values, i)), \
     for [i=1:nfiles] word(files, i) \
       using 'q':(column('allowed') == 1 ? column('lambda') : NaN) with points pt 7 ps 0.7 \
       lc rgb color(i) notitle, \
     NaN with points pt 7 ps 0.7 lc rgb 'black' \
       title (Sv ne '' ? sprintf('allowed modes q = 2{/Symbol p}j/S, S = %s', Sv) : 'allowed modes')
