# Sourced by the bench scripts.
# median: the median of the numbers on stdin, one per line.
median() { sort -g | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
# processor: the model name, as the operating system reports it.
processor() { lscpu | sed -n 's/^Model name: *//p' | head -1; }
