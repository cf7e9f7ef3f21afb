"""Navigation: strapdown mechanisation, the solution history by time of validity, stamp ordering."""


