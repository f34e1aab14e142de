%
(deflex example: 2.5D pocket 60 x 40 x 5 mm, corner radius 8 mm, then the outside contour of a 90 x 70 mm)
(part with 10 mm corners, from a 100 x 80 mm aluminium block; workpiece frame at the block's top centre,)
(z up, mm; 10 mm flat end mill, 3 flutes; slot first, then climb side passes in two 2.5 mm steps)
O2001
N10 G21 G90 G94 G17 G40 G49 G80
N20 G54
N30 T1 M6 (D10 FLAT END MILL 3FL)
N40 S15000 M3
N50 G0 X-25. Y0.
N60 G43 Z15. H1 M8
(level 1: ramp along the slot to z -2.5, slot back, three side passes of 5 mm)
N70 G0 Z1.
N80 G1 X25. Z-2.5 F800.
N90 G1 X-25. F2000.
N100 G1 Y-2. F2000.
N110 G3 X-22. Y-5. I3. J0.
N120 G1 X22.
N130 G3 X25. Y-2. I0. J3.
N140 G1 Y2.
N150 G3 X22. Y5. I-3. J0.
N160 G1 X-22.
N170 G3 X-25. Y2. I0. J-3.
N180 G1 Y0.
N190 G1 Y-7. F2000.
N200 G3 X-22. Y-10. I3. J0.
N210 G1 X22.
N220 G3 X25. Y-7. I0. J3.
N230 G1 Y7.
N240 G3 X22. Y10. I-3. J0.
N250 G1 X-22.
N260 G3 X-25. Y7. I0. J-3.
N270 G1 Y0.
N280 G1 Y-12. F2000.
N290 G3 X-22. Y-15. I3. J0.
N300 G1 X22.
N310 G3 X25. Y-12. I0. J3.
N320 G1 Y12.
N330 G3 X22. Y15. I-3. J0.
N340 G1 X-22.
N350 G3 X-25. Y12. I0. J-3.
N360 G1 Y0.
(level 2: ramp along the slot to z -5.0, slot back, three side passes of 5 mm)
N370 G1 X25. Z-5. F800.
N380 G1 X-25. F2000.
N390 G1 Y-2. F2000.
N400 G3 X-22. Y-5. I3. J0.
N410 G1 X22.
N420 G3 X25. Y-2. I0. J3.
N430 G1 Y2.
N440 G3 X22. Y5. I-3. J0.
N450 G1 X-22.
N460 G3 X-25. Y2. I0. J-3.
N470 G1 Y0.
N480 G1 Y-7. F2000.
N490 G3 X-22. Y-10. I3. J0.
N500 G1 X22.
N510 G3 X25. Y-7. I0. J3.
N520 G1 Y7.
N530 G3 X22. Y10. I-3. J0.
N540 G1 X-22.
N550 G3 X-25. Y7. I0. J-3.
N560 G1 Y0.
N570 G1 Y-12. F2000.
N580 G3 X-22. Y-15. I3. J0.
N590 G1 X22.
N600 G3 X25. Y-12. I0. J3.
N610 G1 Y12.
N620 G3 X22. Y15. I-3. J0.
N630 G1 X-22.
N640 G3 X-25. Y12. I0. J-3.
N650 G1 Y0.
N660 G0 Z15.
(outside contour: part 90 x 70 mm, corners 10 mm; tool centre 5 mm outside, corners 15 mm; climb, clockwise)
N670 G0 X-65. Y0.
N680 G0 Z1.
N690 G1 Z-5. F800.
N700 G1 X-50. F1500.
N710 G1 Y25. F2000.
N720 G2 X-35. Y40. I15. J0.
N730 G1 X35.
N740 G2 X50. Y25. I0. J-15.
N750 G1 Y-25.
N760 G2 X35. Y-40. I-15. J0.
N770 G1 X-35.
N780 G2 X-50. Y-25. I0. J15.
N790 G1 Y0.
N800 G1 X-65.
N810 G0 Z15. M9
N820 M5
N830 G0 X0. Y0.
N840 M30
%
