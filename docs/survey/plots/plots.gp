set terminal svg size 900,600 dynamic background rgb 'white' noenhanced
set grid
set output 'fig2_trajectories_eq7.svg'
set title 'Fig. 2: joint positions of the excitation designed for Eq. 7 (cond(K) minimised, L = 5, f_f = 0.1 Hz)'
set key outside
set xlabel 't [s]'
set ylabel 'q [rad]'
plot for [j=1:6] 'trajectory_eq7.dat' u 1:(column(j+1)) w l lw 2 t sprintf('joint %d', j)
set output 'fig2_trajectories_eq4.svg'
set title 'Fig. 2: joint positions of the excitation designed for Eq. 4 (cond(K) minimised, L = 5, f_f = 0.1 Hz)'
set key outside
set xlabel 't [s]'
set ylabel 'q [rad]'
plot for [j=1:6] 'trajectory_eq4.dat' u 1:(column(j+1)) w l lw 2 t sprintf('joint %d', j)
set output 'residual_rms_eq7.svg'
set terminal svg size 1000,900 dynamic background rgb 'white' noenhanced
set multiplot layout 2,1 title 'RMS torque residual per joint and method, Eq. 7 runs'
set style data histograms
set style histogram cluster gap 1
set style fill solid 0.9 noborder
set xlabel 'joint'
set ylabel 'RMS(tau - tau_hat) [Nm]'
set logscale y
set format y '%g'
set key outside right top font ',9'
set title 'without noise'
plot 'residual_rms_eq7.dat' index 0 u 2:xtic(1) t 'Kalman', 'residual_rms_eq7.dat' index 0 u 3 t 'exponential forgetting', 'residual_rms_eq7.dat' index 0 u 4 t 'genetic algorithm', 'residual_rms_eq7.dat' index 0 u 5 t 'gradient descent', 'residual_rms_eq7.dat' index 0 u 6 t 'particle filter', 'residual_rms_eq7.dat' index 0 u 7 t 'physically consistent LS', 'residual_rms_eq7.dat' index 0 u 8 t 'pseudo-inverse'
set title 'with Table 7 noise'
plot 'residual_rms_eq7.dat' index 1 u 2:xtic(1) t 'Kalman', 'residual_rms_eq7.dat' index 1 u 3 t 'exponential forgetting', 'residual_rms_eq7.dat' index 1 u 4 t 'genetic algorithm', 'residual_rms_eq7.dat' index 1 u 5 t 'gradient descent', 'residual_rms_eq7.dat' index 1 u 6 t 'particle filter', 'residual_rms_eq7.dat' index 1 u 7 t 'physically consistent LS', 'residual_rms_eq7.dat' index 1 u 8 t 'pseudo-inverse'
unset multiplot
unset logscale y
set format y
set style data lines
set terminal svg size 900,600 dynamic background rgb 'white' noenhanced
set output 'residual_rms_eq4.svg'
set terminal svg size 1000,900 dynamic background rgb 'white' noenhanced
set multiplot layout 2,1 title 'RMS torque residual per joint and method, Eq. 4 runs'
set style data histograms
set style histogram cluster gap 1
set style fill solid 0.9 noborder
set xlabel 'joint'
set ylabel 'RMS(tau - tau_hat) [Nm]'
set logscale y
set format y '%g'
set key outside right top font ',9'
set title 'without noise'
plot 'residual_rms_eq4.dat' index 0 u 2:xtic(1) t 'exponential forgetting', 'residual_rms_eq4.dat' index 0 u 3 t 'extended Kalman', 'residual_rms_eq4.dat' index 0 u 4 t 'genetic algorithm', 'residual_rms_eq4.dat' index 0 u 5 t 'gradient descent', 'residual_rms_eq4.dat' index 0 u 6 t 'particle filter', 'residual_rms_eq4.dat' index 0 u 7 t 'physically consistent LS'
set title 'with Table 7 noise'
plot 'residual_rms_eq4.dat' index 1 u 2:xtic(1) t 'exponential forgetting', 'residual_rms_eq4.dat' index 1 u 3 t 'extended Kalman', 'residual_rms_eq4.dat' index 1 u 4 t 'genetic algorithm', 'residual_rms_eq4.dat' index 1 u 5 t 'gradient descent', 'residual_rms_eq4.dat' index 1 u 6 t 'particle filter', 'residual_rms_eq4.dat' index 1 u 7 t 'physically consistent LS'
unset multiplot
unset logscale y
set format y
set style data lines
set terminal svg size 900,600 dynamic background rgb 'white' noenhanced
set output 'fig4_tracking_eq7.svg'
set terminal svg size 900,900 dynamic background rgb 'white' noenhanced
set multiplot layout 3,1 title 'Fig. 4: following beta of joint 3, Eq. 7 run with Table 7 noise'
set key inside top left opaque font ',9'
set xlabel 'N (sample)'
set ylabel 'beta_3 [Nm s/rad]'
set yrange [0:100]
set title 'step change'
plot 'tracking_eq7.dat' index 0 u 1:2 w l lw 3 lc rgb 'black' t 'beta (set)', '' index 0 every 4 u 1:3 w l t 'Kalman', '' index 0 every 4 u 1:4 w l t 'exponential forgetting', '' index 0 every 4 u 1:5 w l t 'physically consistent LS + forgetting'
set title 'ramp change'
plot 'tracking_eq7.dat' index 1 u 1:2 w l lw 3 lc rgb 'black' t 'beta (set)', '' index 1 every 4 u 1:3 w l t 'Kalman', '' index 1 every 4 u 1:4 w l t 'exponential forgetting', '' index 1 every 4 u 1:5 w l t 'physically consistent LS + forgetting'
set title 'second order change'
plot 'tracking_eq7.dat' index 2 u 1:2 w l lw 3 lc rgb 'black' t 'beta (set)', '' index 2 every 4 u 1:3 w l t 'Kalman', '' index 2 every 4 u 1:4 w l t 'exponential forgetting', '' index 2 every 4 u 1:5 w l t 'physically consistent LS + forgetting'
unset multiplot
set autoscale y
set terminal svg size 900,600 dynamic background rgb 'white' noenhanced
set output 'fig4_tracking_eq4.svg'
set terminal svg size 900,900 dynamic background rgb 'white' noenhanced
set multiplot layout 3,1 title 'Fig. 4: following beta of joint 3, Eq. 4 run with Table 7 noise'
set key inside top left opaque font ',9'
set xlabel 'N (sample)'
set ylabel 'beta_3 [Nm s/rad]'
set yrange [0:100]
set title 'step change'
plot 'tracking_eq4.dat' index 0 u 1:2 w l lw 3 lc rgb 'black' t 'beta (set)', '' index 0 every 4 u 1:3 w l t 'extended Kalman', '' index 0 every 4 u 1:4 w l t 'exponential forgetting (Eq. 4)', '' index 0 every 4 u 1:5 w l t 'physically consistent LS + forgetting (Eq. 4)'
set title 'ramp change'
plot 'tracking_eq4.dat' index 1 u 1:2 w l lw 3 lc rgb 'black' t 'beta (set)', '' index 1 every 4 u 1:3 w l t 'extended Kalman', '' index 1 every 4 u 1:4 w l t 'exponential forgetting (Eq. 4)', '' index 1 every 4 u 1:5 w l t 'physically consistent LS + forgetting (Eq. 4)'
set title 'second order change'
plot 'tracking_eq4.dat' index 2 u 1:2 w l lw 3 lc rgb 'black' t 'beta (set)', '' index 2 every 4 u 1:3 w l t 'extended Kalman', '' index 2 every 4 u 1:4 w l t 'exponential forgetting (Eq. 4)', '' index 2 every 4 u 1:5 w l t 'physically consistent LS + forgetting (Eq. 4)'
unset multiplot
set autoscale y
set terminal svg size 900,600 dynamic background rgb 'white' noenhanced
