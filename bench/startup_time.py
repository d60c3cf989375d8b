# Process start-up: median wall and CPU (user + sys) time of a command over many runs,
# binaries alternated (docs/benchmarks.md "Process start").
#   python3 bench/startup_time.py N BIN1,BIN2,... ARGS...
import os, subprocess, sys, time, statistics
def t(cmd):
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, _, ru = os.wait4(p.pid, 0)
    return time.perf_counter() - t0, ru.ru_utime + ru.ru_stime
n = int(sys.argv[1]); bins = sys.argv[2].split(','); args = sys.argv[3:]
res = {b: [] for b in bins}
for i in range(n):
    for b in bins: res[b].append(t([b] + args))
for b in bins:
    w = sorted(x[0] for x in res[b]); c = sorted(x[1] for x in res[b])
    print(f"{b:28s} wall median {1000*statistics.median(w):6.2f} ms (p10 {1000*w[len(w)//10]:6.2f})   CPU median {1000*statistics.median(c):6.2f} ms  (n={n})")
