; Arcs in the XZ plane (G18, I/K centre offsets), a half circle each way.
G21 G90 G18
G01 X-80 Y0 Z0
G03 X80 Z0 I80 K0
G02 X-80 Z0 I-80 K0
