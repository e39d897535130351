"""Tolerances of the tank tests, each with its reason (one place, imported by the tests)."""

#: Agreement of the two exact solvers (Ritz vs FEM), relative, on lambda. Acceptance
#: criterion of issue 4; both are converged to ~1e-7 or better except Ritz above 85 %
#: fill, where it converges algebraically (measured 6e-6 at 90 % with degree 80).
LAMBDA_AGREEMENT = 1e-5
#: Agreement of masses (relative to the liquid mass) and heights (relative to R): issue 4.
MASS_HEIGHT_AGREEMENT = 1e-4
#: McIver (1993) gives the half-full sphere's lambda_1 R to 5 digits, 1.5602.
MCIVER = 1e-4
#: Closed forms for the cylinder (NASA SP-106): issue 4 asks 1e-5; both solvers are
#: exponentially convergent there (measured < 2e-8).
CLOSED_FORM = 1e-5
#: Table 8 damping values are printed to 3 decimals in % critical: one unit of the last
#: digit of 0.703 % is 0.14 %; the issue asks 0.1 % relative.
TABLE_DAMPING_REL = 1e-3
#: The seed tables print 3 decimals: one unit in the last digit.
TABLE_UNIT = 1e-3
