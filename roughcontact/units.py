"""SI values of the units that configurations, file keys and reports use.

Inside the library every quantity is SI (metres, pascals); these constants
convert at the edges only (the configuration's ``*_mm``, ``*_um`` and
``*_MPa`` keys, labels and reports).
"""

#: One millimetre [m].
MM = 1e-3
#: One micrometre [m].
UM = 1e-6
#: One megapascal [Pa].
MPA = 1e6
#: One gigabyte [bytes] (decimal, as memory is reported by schedulers).
GB = 1e9
