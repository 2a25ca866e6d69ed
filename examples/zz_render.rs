fn main() {
    for a in std::env::args().skip(1) {
        let svg = std::fs::read_to_string(&a).unwrap();
        let out = std::path::Path::new("/tmp/fig").join(
            std::path::Path::new(&a)
                .with_extension("png")
                .file_name()
                .unwrap(),
        );
        cablevib::report::figure::write_figure(
            &out,
            &svg,
            cablevib::report::figure::FigureFormat::Png,
        )
        .unwrap();
        println!("{}", out.display());
    }
}
