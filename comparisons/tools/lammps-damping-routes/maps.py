import math
def c(e): return 1.2728-4.2783*e+11.087*e**2-22.348*e**3+27.467*e**4-18.022*e**5+4.8218*e**6
def bisect(f, a, b, n=200):
    fa = f(a)
    for _ in range(n):
        m = 0.5*(a+b); fm = f(m)
        if (fm > 0) == (fa > 0): a, fa = m, fm
        else: b = m
    return 0.5*(a+b)
def tsuji_e(target, lo, hi): return bisect(lambda e: c(e)-target, lo, hi)
def cr_hertz(e): l = math.log(e); return -math.sqrt(5)*l/math.sqrt(math.pi**2+l*l)
def cr_hooke(e): l = math.log(e); return -2*l/math.sqrt(math.pi**2+l*l)
def cr_e(dtarget, kind):
    # invert d = -K l / sqrt(pi^2+l^2)  => l = -pi d / sqrt(K^2-d^2)
    K = math.sqrt(5) if kind == 'hertz' else 2.0
    if dtarget >= K: return None
    return math.exp(-math.pi*dtarget/math.sqrt(K*K-dtarget*dtarget))
if __name__ == "__main__":
    xs = [i/1000 for i in range(0, 1601)]
    mn = min(xs, key=c); print("c min at e=%.4f c=%.6g; c(0)=%.6g c(1)=%.6g" % (mn, c(mn), c(0), c(1)))
    for e in (1.05, 1.1, 1.2, 1.3, 1.5, 2): print("c(%g)=%.5g" % (e, c(e)))
    # derivative sign on [0,1]
    print("monotone dec on [0,mn]:", all(c(xs[i+1]) < c(xs[i]) for i in range(int(mn*1000))))
