# call plotdir.'/logtics.gp' AXIS LO HI: labelled tick marks m x 10^k on
# the log axis AXIS (x, y, y2) between LO and HI, the mantissas m denser
# the shorter the range (1, 2, 5 over one to three decades; 10^k alone past
# three).  gnuplot's own marks on a log axis are the powers of
# ten only: a range under two decades shows one label or none.
lt_lo = real(ARG2)
lt_hi = real(ARG3)
lt_k0 = floor(log10(lt_lo))
lt_k1 = ceil(log10(lt_hi))
lt_span = log10(lt_hi / lt_lo)
lt_ms = lt_span > 3 ? '1' : lt_span > 1.2 ? '1 2 5' : lt_span > 0.5 ? '1 1.5 2 3 5 7' : \
        '1 1.2 1.5 2 2.5 3 4 5 6 7 8 9'
lt_list = ''
do for [lt_k = lt_k0:lt_k1] {
    do for [lt_m in lt_ms] {
        lt_v = real(lt_m) * 10.0**lt_k
        if (lt_v >= lt_lo * (1 - 1e-9) && lt_v <= lt_hi * (1 + 1e-9)) {
            lt_list = lt_list.(lt_list eq '' ? '' : ', ').sprintf('"%g" %.17g', lt_v, lt_v)
        }
    }
}
if (lt_list ne '') { eval sprintf('set %stics (%s)', ARG1, lt_list) }
