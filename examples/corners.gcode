(A 100 mm square and a zigzag at F3000, in the IRB 140's workspace. It selects no)
(path mode: compare --mode G61, exact stop, with --mode G64 --tolerance 0.5.)
G21 G90
G0 X450 Y-50 Z400
G1 X550 F3000
Y50
X450
Y-50
X470 Y-20
X490 Y-50
X510 Y-20
X530 Y-50
