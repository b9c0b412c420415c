// The documentation a user has: README.md and docs/ point at files of the repository, never outside it.
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <iterator>
#include <regex>
#include <string>
#include <vector>

namespace gust::test {
namespace {

namespace fs = std::filesystem;

const fs::path kRoot = fs::weakly_canonical(GUST_SOURCE_DIR);

/// README.md, CONTRIBUTING.md, assets/README.md and every page of docs/.
std::vector<fs::path> pages() {
    std::vector<fs::path> out = {kRoot / "README.md", kRoot / "CONTRIBUTING.md",
                                 kRoot / "assets" / "README.md"};
    for (const auto& entry : fs::directory_iterator(kRoot / "docs"))
        if (entry.path().extension() == ".md") out.push_back(entry.path());
    return out;
}

std::string text_of(const fs::path& path) {
    std::ifstream in(path);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(Docs, everyLinkPointsAtAFileInTheRepository) {
    const std::regex link(R"(\]\(([^)\s]+)\))");
    int links = 0;
    for (const fs::path& page : pages()) {
        const std::string text = text_of(page);
        for (std::sregex_iterator it(text.begin(), text.end(), link), end; it != end; ++it) {
            std::string target = (*it)[1].str();
            if (target.rfind("http://", 0) == 0 || target.rfind("https://", 0) == 0 || target[0] == '#')
                continue;
            target = target.substr(0, target.find('#'));
            const fs::path resolved = fs::weakly_canonical(page.parent_path() / target);
            ++links;
            EXPECT_TRUE(fs::exists(resolved)) << page.lexically_relative(kRoot) << ": " << target;
            const std::string relative = resolved.lexically_relative(kRoot).string();
            EXPECT_FALSE(relative.empty() || relative.rfind("..", 0) == 0)
                << page.lexically_relative(kRoot) << ": " << target << " is outside the repository";
        }
    }
    EXPECT_GT(links, 20) << "the pages link to each other";
}

TEST(Docs, noPageNamesTheProjectWorkspaceOutsideTheRepository) {
    // The project's workspace kept the design card, the seed report and the asset collection beside the
    // repository (../shared); a user has only the repository, wherever it was cloned.
    const std::string outside[] = {"../shared", (kRoot.parent_path() / "shared").string(), kRoot.string()};
    for (const fs::path& page : pages()) {
        const std::string text = text_of(page);
        for (const std::string& name : outside)
            EXPECT_EQ(text.find(name), std::string::npos)
                << page.lexically_relative(kRoot) << " mentions " << name;
    }
}

TEST(Docs, theReadmeLinksTheDesignAndTheCommandLine) {
    const std::string readme = text_of(kRoot / "README.md");
    EXPECT_NE(readme.find("(docs/design.md)"), std::string::npos);
    EXPECT_NE(readme.find("(docs/cli.md)"), std::string::npos);
}

} // namespace
} // namespace gust::test
