$ Nastran file written by meshio v5.3.5
BEGIN BULK
GRID*   1                                          0.E+0           0.E+0
*                  0.E+0
GRID*   2                                          1.E+0           0.E+0
*                  0.E+0
GRID*   3                                          1.E+0           1.E+0
*                  0.E+0
GRID*   4                                          0.E+0           1.E+0
*                  0.E+0
GRID*   5                                          5.E-1           5.E-1
*                  0.E+0
CBAR    1               1       2       
CBAR    2               2       3       
CBAR    3               3       4       
CBAR    4               4       1       
CTRIA3  5               1       2       5       
CTRIA3  6               2       3       5       
CTRIA3  7               3       4       5       
CTRIA3  8               4       1       5       
ENDDATA
