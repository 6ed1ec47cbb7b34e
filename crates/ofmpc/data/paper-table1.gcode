%
(Testing trajectory of the paper, Table I, section IV. Coordinates in mm as printed.)
(Orientation is constant: tool axis along the base x axis; the reader ignores orientation.)
G21 G90 (millimetres, absolute coordinates)
(WORK OFFSET: read in the robot base frame, the paper's path passes about 0.2 m from the)
(shoulder at X230 and axis 3 would need about 74 deg, beyond its +50 deg limit. The paper)
(does not say where the part is, so it is placed with a work offset of X150 Y0 Z-250 mm:)
(the path then runs at x 380..780 mm, z 150 mm, every joint at least 10 deg inside its)
(limits, clear of the wrist singularity. Base-frame point = program point + offset.)
G10 L2 P1 X150 Y0 Z-250
G54
(PLANE: the paper's first line is N010 G19, but its arcs give I/J centre offsets and all)
(points lie at Z400: it is an XY-plane program. In the YZ plane of G19 the arcs would have)
(radius 0 and a G-code reader must reject them, so this copy uses G17.)
N010 G17
N020 G00 X630 Y-200 Z400
N030 G00 X630 Y200 Z400
N040 G00 X630 Y0 Z400
N050 G02 X430 Y-200 Z400 I-200 J0 K0
N060 G02 X430 Y200 Z400 I0 J200 K0
N070 G02 X630 Y0 Z400 I0 J-200 K0
N080 G00 X630 Y-200 Z400
N090 G00 X630 Y200 Z400
N010 G00 X630 Y0 Z400 (the paper repeats the label N010: labels, not keys)
M30
%
