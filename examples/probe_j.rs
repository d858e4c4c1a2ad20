use partlife::strength::flaws::{fit, Populations};
fn main() {
    let text = std::fs::read_to_string("datasets/real/jahanmir_silicon_nitride_bend_bars.csv").unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let si = head.iter().position(|h| *h == "strength_original_units").unwrap();
    let bi = head.iter().position(|h| *h == "batch").unwrap();
    for b in ["1", "2"] {
        let x: Vec<f64> = text.lines().skip(1).map(|l| l.split(',').collect::<Vec<_>>()).filter(|v| v[bi] == b).map(|v| v[si].parse::<f64>().unwrap()).collect();
        let one = partlife::weibull::fit_mle(&x).unwrap().mle;
        let l0: f64 = x.iter().map(|v| { let z = v / one.scale; one.shape.ln() - one.scale.ln() + (one.shape - 1.0) * z.ln() - z.powf(one.shape) }).sum();
        for k in [Populations::Mixture, Populations::Competing] {
            let f = fit(k, &x).unwrap();
            println!("batch {b} n {} {k:?}: Λ {:.2} {:?} {}", x.len(), 2.0 * (f.loglik - l0), f.identifiable, f.describe());
        }
    }
}
