// figures.gp of `zwidth run`: the gnuplot script drawing every figure from the
// .dat files beside it.
#include <locale>
#include <sstream>
#include <vector>

#include "model/units.h"
#include "report/report_internal.h"

namespace zwidth::report {

std::string FigureScript(const FigureScriptOptions& o) {
  std::ostringstream gp;
  gp.imbue(std::locale::classic());  // the numbers of the script, whatever the host's locale
  gp << "set datafile missing 'nan'\nset grid\nset key outside right\n"
     << "set linetype 1 lc rgb '#1f77b4' lw 2\nset linetype 2 lc rgb '#d62728' lw 2\n"
     << "set linetype 3 lc rgb '#2ca02c' lw 2\nset linetype 4 lc rgb '#9467bd' lw 2\n"
     << "set linetype 5 lc rgb '#ff7f0e' lw 2\nset linetype 6 lc rgb '#8c564b' lw 2\n";
  std::string dl;
  for (size_t i = 0; i < o.delays.size(); ++i) {  // appended, not (" " + ...): gcc 12's -Wrestrict false positive
    if (i) dl += ' ';
    dl += std::to_string(o.delays[i]);
  }
  gp << "delays = '" << dl << "'\nmodel_delay = " << o.model_delay << "\n";
  std::vector<const char*> terms = {"svg size 900,640 font 'sans,12'"};
  if (o.png) terms.push_back("pngcairo size 900,640 font 'sans,10'");
  for (const char* term : terms) {
    const std::string ext = std::string(term).rfind("svg", 0) == 0 ? "svg" : "png";
    gp << "set terminal " << term << "\n";
    gp << "set output 'bode." << ext << "'\nset multiplot layout 2,1 title 'Bode diagram: measured (" << ident::ToString(o.method) << ") and fitted model (exact ZOH) - Fig. 3'\n"
       << "set logscale x\nset logscale y\nset format y '10^{%L}'\nset ylabel 'magnitude [" << model::Units(o.linear).H << "]'\nunset xlabel\n"
       << "plot 'bode.dat' index 0 u 1:2 w l lc rgb '#1f77b4' t 'measured, fitted band', "
       << "'' index 1 u 1:2 w p pt 7 ps 0.25 lc rgb '#bbbbbb' t 'measured, not used', "
       << "'' index 2 u 1:2 w l lw 2 lc rgb 'black' t 'fitted model'\n"
       << "unset logscale y\nset format y '%g'\nset ylabel 'phase [deg]'\nset xlabel 'frequency [Hz]'\n"
       << "plot 'bode.dat' index 0 u 1:3 w l lc rgb '#1f77b4' t 'measured, fitted band', "
       << "'' index 1 u 1:3 w p pt 7 ps 0.25 lc rgb '#bbbbbb' t 'measured, not used', "
       << "'' index 2 u 1:3 w l lw 2 lc rgb 'black' t 'fitted model'\nunset multiplot\n";
    gp << "set output 'coherence." << ext << "'\nset title 'Magnitude-squared coherence'\nset xlabel 'frequency [Hz]'\nset ylabel 'coherence [-]'\nset yrange [0:1.05]\n"
       << (o.joint ? "plot 'bode.dat' index 3 u 1:2 w l lc rgb '#1f77b4' t 'r -> u', '' index 3 u 1:3 w l lc rgb '#d62728' t 'r -> y'\n"
                 : "plot 'bode.dat' index 3 u 1:2 w l lc rgb '#1f77b4' t 'coherence'\n")
       << "set yrange [*:*]\nunset logscale x\nunset title\n";
    gp << "set output 'kcr." << ext << "'\nset multiplot layout 2,1 title 'Critical stiffness and ultimate frequency vs damping - Fig. 6 / Fig. 10'\n"
       << "set xlabel 'B [" << model::Units(o.linear).B << "]'\nset ylabel 'K_{CR} [" << model::Units(o.linear).K << "]'\n"
       << "plot for [i=1:words(delays)] 'kcr_model.dat' index i-1 u 1:2 w l lt i t sprintf('model, d = %s + %d', word(delays,i), model_delay)"
       << (o.have_ref ? ", for [i=1:words(delays)] 'kcr_reference.dat' index i-1 u 1:2 w l lt i dt 2 lw 1 t 'reference, d='.word(delays,i)" : "")
       << (o.table1 ? ", 'table2.dat' u 2:3 w p pt 7 ps 0.8 lc rgb 'red' t 'Table II (relay)'" : "") << "\n"
       << "set logscale y\nset ylabel 'f_{CR} [Hz]'\n"
       << "plot for [i=1:words(delays)] 'kcr_model.dat' index i-1 u 1:3 w l lt i t sprintf('model, d = %s + %d', word(delays,i), model_delay)"
       << (o.table1 ? ", 'table2.dat' u 2:4 w p pt 7 ps 0.8 lc rgb 'red' t 'Table II (relay)'" : "") << "\nunset logscale y\nunset multiplot\n";
    gp << "set output 'region." << ext << "'\nset multiplot layout " << o.delays.size()
       << ",1 title 'Z-width: stable (B, K) region per delay (shaded), K_{CR}(B) and its +-2 sigma band'\n"
       << "set xlabel 'B [" << model::Units(o.linear).B << "]'\nset ylabel 'K [" << model::Units(o.linear).K
       << "]'\nset yrange [0:" << o.k_clip << "]\n"
       << "do for [i=1:words(delays)] {\n"
       << "  set title sprintf('delay: loop %s + model %d = %d samples', word(delays,i), model_delay, word(delays,i) + model_delay)\n"
       << "  plot 'region_model.dat' index i-1 u 1:2:3 w filledcurves fs solid 1.0 noborder lc rgb '#9ecae1' notitle, "
       << "keyentry w l lw 2 lc rgb '#9ecae1' t 'stable', "
       << "'kcr_model.dat' index i-1 u 1:5:6 w filledcurves fs transparent solid 0.35 "
       << "lc rgb '#d62728' t 'K_{CR} +- 2 sigma', '' index i-1 u 1:2 w l lw 2 lc rgb '#08306b' t 'K_{CR}(B)'\n"
       << "}\nunset multiplot\nset yrange [*:*]\nunset title\n";
    gp << "set output 'loop." << ext << "'\nset multiplot layout " << o.delays.size()
       << ",1 title 'Stable region without and with a " << o.report_filter_hz
       << " Hz velocity low-pass; passivity boundary K_P(B) (Colgate-Schenkel)'\n"
       << "set xlabel 'B [" << model::Units(o.linear).B << "]'\nset ylabel 'K [" << model::Units(o.linear).K
       << "]'\nset yrange [0:" << o.k_clip_loop << "]\n"
       << "do for [i=1:words(delays)] {\n"
       << "  set title sprintf('delay: loop %s + model %d = %d samples', word(delays,i), model_delay, word(delays,i) + model_delay)\n"
       << "  plot 'loop_region.dat' index 2*i-2 u 1:2:3:4 w vectors nohead lc rgb '#fdae6b' t 'stable, filtered', "
       << "'' index 2*i-1 u 1:2:3:4 w vectors nohead lc rgb '#6baed6' t 'stable, raw difference', "
       << "'loop_passive.dat' index i-1 u 1:2 w l lw 2 lc rgb 'black' t 'K_P, raw', '' index i-1 u 1:3 w l lw 2 dt 2 lc rgb '#7f2704' t 'K_P, filtered'\n"
       << "}\nunset multiplot\nset yrange [*:*]\nunset title\n";
    gp << "set output 'rigid." << ext << "'\nset title 'With the vibration modes and without (rigid body only) - Fig. 7'\n"
       << "set xlabel 'B [" << model::Units(o.linear).B << "]'\nset ylabel 'K_{CR} [" << model::Units(o.linear).K << "]'\n"
       << "plot for [i=1:words(delays)] 'kcr_model.dat' index i-1 u 1:2 w l lt i t 'with modes, d='.word(delays,i), "
       << "for [i=1:words(delays)] 'kcr_rigid.dat' index i-1 u 1:2 w l lt i dt 2 t 'rigid only, d='.word(delays,i)\nunset title\n";
  }
  return gp.str();
}

}  // namespace zwidth::report
